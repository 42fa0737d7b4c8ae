#!/usr/bin/env bash
# Prints one SHA-256 per output of the programs on the bundled scenes at a small resolution:
# render, grad (every --boundary method), fd and reverse, at a fixed seed. Two builds that print
# the same lines write the same bytes; a refactor that must not change behaviour is checked with
#   bash tools/output-digests.sh build-before > before.txt; bash tools/output-digests.sh build > after.txt
#   diff before.txt after.txt
# Usage: bash tools/output-digests.sh [BUILD_DIR]   (default: build; run from anywhere)
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="$(cd "${1:-$root/build}" && pwd)"
qsil="$build/qsil"
out="$(mktemp -d)"
trap 'rm -rf "$out"' EXIT
cd "$root"
common=(-D res=32 --spp 8 --seed 7 --threads 2 -q)
digest() {
  case $2 in
    *.exr) printf '%-40s %s\n' "$1" "$(/usr/bin/python3 "$root/tools/exr_digest.py" "$2")" ;;
    *) printf '%-40s %s\n' "$1" "$(sha256sum "$2" | cut -c1-16)" ;;
  esac
}
for scene in spot-mirror shadow-quad direct sunk; do
  case $scene in
    shadow-quad) param=object:translate:0,1,0 ;;
    *) param=spot:translate:0,1,0 ;;
  esac
  "$qsil" render "scenes/$scene.xml" "${common[@]}" -o "$out/r.exr" >&2
  digest "$scene render" "$out/r.exr"
  for method in quadric quadric-box vsphere vsphere-solid uniform none was projective; do
    "$qsil" grad "scenes/$scene.xml" "${common[@]}" --param "$param" --boundary "$method" -o "$out/g.exr" >&2
    digest "$scene grad $method" "$out/g.exr"
  done
  "$qsil" fd "scenes/$scene.xml" "${common[@]}" --param "$param" -o "$out/f.exr" >&2
  digest "$scene fd" "$out/f.exr"
  "$qsil" reverse "scenes/$scene.xml" "${common[@]}" --shape "${param%%:*}" --adjoint "$out/r.exr" \
    --image "$out/i.exr" -o "$out/v.npy" >&2
  digest "$scene reverse" "$out/v.npy"
  digest "$scene reverse image" "$out/i.exr"
done

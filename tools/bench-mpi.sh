#!/usr/bin/env bash
# Speed-up of qsil under MPI (README "Running on a cluster"): `render` and `grad` of
# scenes/spot-mirror.xml as one process on 1 thread, as 2 MPI ranks of 1 thread each
# (mpirun -np 2), and, for comparison, as one process on 2 threads. Prints a Markdown table of wall
# time (process start to exit: MPI start-up, scene loading, set-up, render, film transfer, output),
# the time of qsil's summary line (render: the render; grad: set-up + render), the speed-up of the wall time over 1 process x 1
# thread, the CPU time of all processes together (the work's cost whatever else the machine runs),
# and the largest resident memory of one process.
# Usage: bash tools/bench-mpi.sh [BUILD_DIR] [RES] [RENDER_SPP] [GRAD_SPP]
#        (defaults: build, 256, 64, 16)
# Needs a build with MPI (QSIL_MPI) and Open MPI's mpirun. On a 2-core machine the 2 ranks and the
# 2 threads compete for the same cores: the table compares ways of using them, not a cluster.
set -euo pipefail
cd "$(dirname "$0")/.."
build="${1:-build}"
res="${2:-256}"
render_spp="${3:-64}"
grad_spp="${4:-16}"
qsil="$build/qsil"
[ -x "$qsil" ] || { echo "bench-mpi: $qsil not found (build first)" >&2; exit 2; }
command -v mpirun >/dev/null || { echo "bench-mpi: mpirun not found (apt-get install openmpi-bin)" >&2; exit 2; }
[ -x /usr/bin/time ] || { echo "bench-mpi: /usr/bin/time not found (apt-get install time)" >&2; exit 2; }
# Root is allowed (CI machines); no single-copy shared memory (some containers forbid it).
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_btl_vader_single_copy_mechanism=none
work="$(mktemp -d "${TMPDIR:-/tmp}/qsil-bench-mpi.XXXXXX")"
trap 'rm -rf "$work"' EXIT

# run LABEL RANKS THREADS ARGS...: one line of the table.
base_wall=""
run() {
  local label="$1" ranks="$2" threads="$3"
  shift 3
  local launcher=()
  if [ "$ranks" -gt 0 ]; then launcher=(mpirun -q --oversubscribe --bind-to none -np "$ranks"); fi
  rm -f "$work/rss"
  local t0 t1
  t0=$(date +%s.%N)
  "${launcher[@]}" /usr/bin/time -a -o "$work/rss" -f "%M %U %S" "$qsil" "$@" --threads "$threads" -q \
    -o "$work/out.exr" >"$work/stdout"
  t1=$(date +%s.%N)
  local wall render rss cpu
  wall=$(awk -v a="$t0" -v b="$t1" 'BEGIN { print b - a }')
  # CPU time (user + system) summed over the processes: what the work costs whatever else runs.
  cpu=$(awk '{ c += $2 + $3 } END { printf "%.2f", c }' "$work/rss")
  # The summary's first "N.NNN s": the render time (render) or the total with set-up (grad).
  render=$(grep -oE '[0-9]+\.[0-9]+ s' "$work/stdout" | head -1 | cut -d' ' -f1)
  rss=$(awk '$1 > m { m = $1 } END { print m }' "$work/rss")
  [ -n "$base_wall" ] || base_wall="$wall"
  printf '| %s | %s | %.2f | %s | %.2fx | %s | %d |\n' "$label" \
    "$([ "$ranks" -gt 0 ] && echo "mpirun -np $ranks, --threads $threads" || echo "1 process, --threads $threads")" \
    "$wall" "$render" "$(awk -v a="$base_wall" -v b="$wall" 'BEGIN { print a / b }')" "$cpu" "$((rss / 1024))"
}

echo "qsil under MPI: scenes/spot-mirror.xml at ${res}x${res} (render $render_spp spp, grad $grad_spp spp)," \
  "$(nproc) cores, $(mpirun --version | head -1)"
echo
echo "| command | processes x threads | wall s | qsil s | speed-up (wall) | CPU s (all processes) | max RSS MiB/process |"
echo "| --- | --- | --- | --- | --- | --- | --- |"
for cmd in render grad; do
  spp="$render_spp"
  [ "$cmd" = grad ] && spp="$grad_spp"
  args=("$cmd" scenes/spot-mirror.xml -D "res=$res" --spp "$spp" --seed 1)
  if [ "$cmd" = grad ]; then args+=(--param spot:translate:0,1,0); fi
  base_wall=""
  run "$cmd" 0 1 "${args[@]}"
  run "$cmd" 2 1 "${args[@]}"
  run "$cmd" 0 2 "${args[@]}"
  run "$cmd" 1 1 "${args[@]}"
done

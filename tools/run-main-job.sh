#!/usr/bin/env bash
# Sets up (Debian packages), builds (Release) and runs qsil's main job on the bundled default
# scene: the image of scenes/spot-mirror.xml, written to out/spot-mirror.exr with a PNG preview.
# Usage: bash tools/run-main-job.sh [BUILD_DIR]   (default: build)
set -euo pipefail
cd "$(dirname "$0")/.."
build="${1:-build}"
bash tools/install-deps.sh
cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=Release
cmake --build "$build" -j"$(nproc)" --target qsil_cli
mkdir -p out
"$build/qsil" render scenes/spot-mirror.xml -o out/spot-mirror.exr --preview out/spot-mirror.png

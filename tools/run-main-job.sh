#!/usr/bin/env bash
# Sets up (Debian packages), builds (Release, without the QSIL_DCHECK checks) and runs qsil's main
# job on the bundled default scene: the gradient image of scenes/spot-mirror.xml with respect to
# Spot's vertical translation (interior term + quadric boundary term), written to
# out/spot-mirror-grad.exr with PNG previews (out/spot-mirror-grad/primal.png and dtheta0.png).
# Usage: bash tools/run-main-job.sh [BUILD_DIR]   (default: build)
set -euo pipefail
cd "$(dirname "$0")/.."
build="${1:-build}"
bash tools/install-deps.sh
cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=Release -DQSIL_DCHECKS=OFF
cmake --build "$build" -j"$(nproc)" --target qsil_cli
mkdir -p out
"$build/qsil" grad scenes/spot-mirror.xml --param spot:translate:0,1,0 --boundary quadric \
  -o out/spot-mirror-grad.exr --preview-dir out/spot-mirror-grad

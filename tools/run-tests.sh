#!/usr/bin/env bash
# Sets up (Debian packages), builds (Release, with the QSIL_DCHECK invariant checks on: the tests
# run with them) and runs the whole test suite with ctest.
# Usage: bash tools/run-tests.sh [BUILD_DIR]   (default: build)
set -euo pipefail
cd "$(dirname "$0")/.."
build="${1:-build}"
bash tools/install-deps.sh
cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=Release -DQSIL_DCHECKS=ON
cmake --build "$build" -j"$(nproc)"
ctest --test-dir "$build" --output-on-failure -j"$(nproc)"

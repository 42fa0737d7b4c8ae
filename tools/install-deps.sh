#!/usr/bin/env bash
# Installs qsil's build and test dependencies from Debian 12 packages (idempotent: packages that are
# already installed are skipped, and apt-get is not called at all when nothing is missing).
# Open MPI (libopenmpi-dev, openmpi-bin) is optional for the build (CMake option QSIL_MPI) and
# installed so that the MPI build and its tests (tests/mpi_cli_test.cpp) run in CI.
set -euo pipefail
packages=(
  build-essential cmake pkg-config
  libembree-dev libeigen3-dev coinor-libclp-dev libopenexr-dev libimath-dev
  libtinyobjloader-dev libtbb-dev libcli11-dev libpugixml-dev
  libcgal-dev libgtest-dev libgmock-dev libbenchmark-dev libstb-dev libpcg-cpp-dev nlohmann-json3-dev
  python3 python3-dev python3-matplotlib python3-numpy python3-scipy python3-pytest pybind11-dev
  libopenmpi-dev openmpi-bin
)
missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi
echo "install-deps: installing ${missing[*]}"
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"

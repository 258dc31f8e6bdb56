#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Installs every build, test and benchmark dependency on Debian 12 (bookworm) with apt.
# Idempotent: packages already present are skipped quickly.
set -euo pipefail
packages=(
  build-essential gfortran cmake pkg-config ninja-build
  clang  # scripts/clang_check.sh
  libvtk9-dev python3-vtk9 xvfb xauth
  libopenmesh-dev
  libegl-dev libgl-dev libegl-mesa0 libgl1-mesa-dri mesa-utils
  libpng-dev nlohmann-json3-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  libzfp-dev libzstd-dev libfpzip-dev
  libopenmpi-dev openmpi-bin  # penumbra_mpi and its tests under mpirun
  libmetis-dev  # METIS partitions in the MPI tests
  libcpp-httplib-dev  # penumbra-view (viewer/)
  libusb-1.0-0-dev  # penumbra-view's 3D mouse
  chromium  # the viewer's browser tests (tests/viewer/browser)
  gmsh  # benchmark meshes (bench/run.sh)
)
source "$(dirname "$0")/apt_install.sh"
apt_install_missing "${packages[@]}"
# playwright-core for the viewer's browser tests, at the version package-lock.json records.
if command -v npm >/dev/null; then
  npm ci --prefix "$(dirname "$0")/../tests/viewer/browser" --no-audit --no-fund --silent
else
  echo "setup: npm not found: the viewer's browser tests will be skipped" >&2
fi

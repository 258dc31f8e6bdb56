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
  gmsh  # benchmark meshes (bench/run.sh)
)
source "$(dirname "$0")/apt_install.sh"
apt_install_missing "${packages[@]}"

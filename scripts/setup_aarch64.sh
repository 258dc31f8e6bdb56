#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Installs what the aarch64 cross build (scripts/cross_aarch64.sh) needs on Debian 12 (bookworm)
# x86-64, with apt: Debian's cross compiler, qemu-user to run the tests, and the arm64 multiarch
# libraries. libopenmesh-dev:arm64 conflicts with the host's VTK development packages, so the
# host's libopenmesh-dev gives the headers (the same on every architecture) and libopenmesh1:arm64
# the library (cmake/toolchains/openmesh). Needs root or sudo. Idempotent: packages already
# present are skipped quickly, and the arm64 architecture is added only once (scripts/apt_install.sh).
set -euo pipefail
packages=(
  cmake ninja-build
  g++-aarch64-linux-gnu qemu-user
  libopenmesh-dev nlohmann-json3-dev  # headers only: used as they are for arm64
  libpng-dev:arm64 libopenmesh1:arm64 libzstd-dev:arm64 libgtest-dev:arm64 libgmock-dev:arm64
)
source "$(dirname "$0")/apt_install.sh"
apt_install_missing "${packages[@]}"

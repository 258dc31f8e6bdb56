#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# scripts/clang_check.sh [BUILD_DIR] -- builds everything with clang and runs the whole test
# suite. Solvers are often built with LLVM-based compilers and build Penumbra with the same one;
# the vector kernels' target regions are spelled for each compiler (compression/src/
# target_region.h), and only a build with each shows that both spellings compile and decode alike.
# Needs what scripts/setup.sh installs. BUILD_DIR defaults to build-clang.
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build-clang}
CC=clang CXX=clang++ cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release
cmake --build "$build"
ctest --test-dir "$build" --output-on-failure -j "$(nproc)"

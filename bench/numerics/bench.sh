# SPDX-License-Identifier: BSD-3-Clause
# usage: numerics  (the scene scaled 1e-15..1e15, moved up to 1e7 diagonals, its field offset up to 1e9 x its range and of magnitude 1e-300..1e300, on every path: CPU/GPU x none/light-volume/occlusion; RMS and largest level difference against the untransformed picture beside the frame time)
# Sourced by bench/run.sh, which provides build_targets, log, holeblock_mesh, $build, $data and
# $frames. Environment: PNB_BENCH_NUMERICS_SCENE (holeblock-100k, the default: generated with gmsh
# on first use; holeblock-1m; grid-aligned), PNB_BENCH_NUMERICS_SIZE (WxH, default 256x256).
# The GPU lines run on a hardware device when EGL lists one, else on Mesa's llvmpipe;
# PNB_EGL_DEVICE / PNB_EGL_LIBRARY choose the EGL device or library.

bench_numerics() {
  build_targets pnb_bench_numerics
  local scene=${PNB_BENCH_NUMERICS_SCENE:-holeblock-100k}
  [ "$scene" = holeblock-1m ] && holeblock_mesh
  [ "$scene" = holeblock-100k ] && holeblock_mesh holeblock-100k 0.34
  log "numerics/$scene: 20 transformations on each path"
  "$build/bench/pnb_bench_numerics" --scene "$scene" --data-dir "$data" --frames "$frames" \
    --size "${PNB_BENCH_NUMERICS_SIZE:-256x256}"
}

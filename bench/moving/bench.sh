# SPDX-License-Identifier: BSD-3-Clause
# usage: moving  (a ~1M-tet mesh whose points move every step: geometry update vs full preparation through pnb_publish_mesh, CPU/GPU x unlit/light volume, with the image RMS between the two; a Lagrangian series' store: segments, ratio, replay RMS)
# Sourced by bench/run.sh, which provides build_targets, log, holeblock_mesh, $build, $data and
# $frames (the steps). Environment: PNB_BENCH_MOVING_SCENE (holeblock-1m, the default: generated
# with gmsh on first use; holeblock-100k; grid-aligned), PNB_BENCH_MOVING_SIZE (WxH, default
# 256x256), PNB_BENCH_MOVING_BACKENDS (default "cpu gpu"; the GPU lines run on a hardware device
# when EGL lists one, else on Mesa's llvmpipe), PNB_BENCH_MOVING_LIGHTING (default
# "none light-volume"), PNB_BENCH_MOVING_STORE_STEPS (the Lagrangian series with a store, default
# 16; 0 leaves its line out).

bench_moving() {
  build_targets pnb_bench_moving
  local scene=${PNB_BENCH_MOVING_SCENE:-holeblock-1m}
  [ "$scene" = holeblock-1m ] && holeblock_mesh
  [ "$scene" = holeblock-100k ] && holeblock_mesh holeblock-100k 0.34
  log "moving/$scene: $frames steps of a swirl, each published as moved points and as a new topology"
  "$build/bench/pnb_bench_moving" --scene "$scene" --data-dir "$data" --frames "$frames" \
    --size "${PNB_BENCH_MOVING_SIZE:-256x256}" --backends "${PNB_BENCH_MOVING_BACKENDS:-cpu gpu}" \
    --lighting "${PNB_BENCH_MOVING_LIGHTING:-none light-volume}" --store-steps "${PNB_BENCH_MOVING_STORE_STEPS:-16}"
}

# SPDX-License-Identifier: BSD-3-Clause
# usage: light   (two-level light volume, Shih et al. Table 2 style: level-0 16^3..256^3 x none/level0-only/two-level, ~1M tets, + light-1m, light-budget)
# Sourced by bench/run.sh, which provides build_targets, log, holeblock_mesh, $root, $build, $data
# and $frames. Environment: PNB_BENCH_LIGHT_SCENE (holeblock-1m, the default, or grid-aligned),
# PNB_BENCH_LIGHT_LEVELS (default "16 32 64 128 256"), PNB_BENCH_LIGHT_SAMPLES (reference
# vertices, default 4000), PNB_BENCH_LIGHT_PARTS (default "sweep 1m gpu budget": which lines to
# print), PNB_BENCH_LIGHT_VERBOSE=1 (per-frame times of the budget run on stderr). Errors are
# against the double-precision transmittance (image and per vertex; see light_bench.cpp). Times
# are wall clock beside cpu_ms (process CPU over all threads), which shows the work apart from
# waiting on a shared machine.

bench_light() {
  build_targets pnb_bench_light
  local scene=${PNB_BENCH_LIGHT_SCENE:-holeblock-1m}
  [ "$scene" = holeblock-1m ] && holeblock_mesh
  log "light/$scene: reference transmittance, then each level-0 size and mode (minutes at 256^3)"
  "$build/bench/pnb_bench_light" --scene "$scene" --data-dir "$data" --frames "$frames" \
    --levels "${PNB_BENCH_LIGHT_LEVELS:-16 32 64 128 256}" --samples "${PNB_BENCH_LIGHT_SAMPLES:-4000}" \
    --parts "${PNB_BENCH_LIGHT_PARTS:-sweep 1m gpu budget}"
}

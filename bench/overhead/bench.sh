# SPDX-License-Identifier: BSD-3-Clause
# usage: overhead  (the examples' solvers on holeblock-100k and holeblock-1m with and without Penumbra, sync and async, unlit / light volume / occlusion, with and without a store, and a moving mesh; then a step budget of one solver step and the adaptive cadence: overhead %, what a rendering step's pnb_execute and publications cost the solver beside one memcpy of what it reads, what the worker costs the solver's own steps, what budgeted steps gave up)
# Sourced by bench/run.sh, which provides build_targets, log, holeblock_mesh, $build and $data.
# Environment: PNB_BENCH_OVERHEAD_SCENES (default "holeblock-100k holeblock-1m"),
# PNB_BENCH_OVERHEAD_RUNS (alternated pairs per configuration, default 3), PNB_BENCH_OVERHEAD_STEPS
# (default 40, rendering every 10th).

bench_overhead() {
  build_targets pnb_bench_overhead
  local scene
  for scene in ${PNB_BENCH_OVERHEAD_SCENES:-holeblock-100k holeblock-1m}; do
    [ "$scene" = holeblock-1m ] && holeblock_mesh
    [ "$scene" = holeblock-100k ] && holeblock_mesh holeblock-100k 0.34
    log "overhead/$scene: the solver alone and with Penumbra, alternated"
    "$build/bench/pnb_bench_overhead" --scene "$scene" --data-dir "$data" --runs "${PNB_BENCH_OVERHEAD_RUNS:-3}" \
      --steps "${PNB_BENCH_OVERHEAD_STEPS:-40}" --every 10
  done
}

# SPDX-License-Identifier: BSD-3-Clause
# usage: viewer  (penumbra-view's views of a 64-step store of holeblock-1m, over HTTP: new camera, new step through the pager, new transfer function, at 512², unlit and with the light volume, beside the RMS against the run's own image)
# Sourced by bench/run.sh, which provides build_targets, log, holeblock_mesh, $build and $data.
# Environment: PNB_BENCH_VIEWER_SCENE (holeblock-1m, the default; holeblock-100k),
# PNB_BENCH_VIEWER_LIGHTING (default "none light-volume"), PNB_BENCH_VIEWER_REQUESTS (requests per
# median, default 7), PNB_BENCH_VIEWER_SIZE (default 512).

bench_viewer() {
  build_targets pnb_bench_viewer
  local scene=${PNB_BENCH_VIEWER_SCENE:-holeblock-1m}
  [ "$scene" = holeblock-1m ] && holeblock_mesh
  [ "$scene" = holeblock-100k ] && holeblock_mesh holeblock-100k 0.34
  log "viewer/$scene: a 64-step run with a store per lighting model (minutes), then views over HTTP"
  "$build/bench/pnb_bench_viewer" --scene "$scene" --data-dir "$data" --steps 64 \
    --size "${PNB_BENCH_VIEWER_SIZE:-512}" --lighting "${PNB_BENCH_VIEWER_LIGHTING:-none light-volume}" \
    --requests "${PNB_BENCH_VIEWER_REQUESTS:-7}"
}

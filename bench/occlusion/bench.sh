# SPDX-License-Identifier: BSD-3-Clause
# usage: occlusion  (cone-traced directional occlusion and shadows: emission-absorption, AO with splits 1/3/7 per point and in object space, AO + shadows; ms per frame beside CIELAB Delta E against Monte Carlo images)
# Sourced by bench/run.sh, which provides build_targets, log, holeblock_mesh, $build, $data and
# $frames. Environment: PNB_BENCH_OCC_SCENES (default "hexblock-hole plate-shadow disk-out-ref holeblock-100k
# grid-aligned"; disk-out-ref is the hex mesh tests/data/disk_out_ref.ex2; holeblock-100k (generated
# with gmsh on first use) the graded hole-block tet mesh small enough for Monte Carlo; holeblock-1m
# is generated with gmsh on first use), PNB_BENCH_OCC_SIZE (WxH, default 512x512),
# PNB_BENCH_OCC_GRID (extinction grid nodes along the longest axis, default 128),
# PNB_BENCH_OCC_PREILLUM (pre-illumination volume resolution, default 64),
# PNB_BENCH_OCC_MC_MAX_POINTS (scenes with more mesh points get no Monte Carlo image and null
# errors, default 60000: the Monte Carlo image costs about 1 ms of rays per point),
# PNB_BENCH_OCC_ALPHA (global attenuation alpha, default 1), PNB_BENCH_OCC_WEIGHT (section
# weight: mean, the default, or thesis for eq. 3-15), PNB_BENCH_OCC_PYRAMID (what the pyramid filters:
# opacity, the default, extinction or step_opacity; occlusion.h), PNB_BENCH_OCC_LEVEL (the level a cone
# section reads: continuous, the default, or thesis for whole levels stepping at r_c = 2 sigma) and PNB_BENCH_OCC_GPU (on, the default: also
# lines with backend "gpu" when the GPU backend is built -- a hardware device, else Mesa's llvmpipe,
# which shows agreement but a CPU's speed; off: CPU lines only) and PNB_BENCH_OCC_MODES (all, the
# default; shadow: only ao+shadow and the hard-shadow lines). PNB_EGL_DEVICE / PNB_EGL_LIBRARY
# choose the EGL device or library.

bench_occlusion() {
  build_targets pnb_bench_occlusion
  local scene bin=$build/bench
  for scene in ${PNB_BENCH_OCC_SCENES:-hexblock-hole plate-shadow disk-out-ref holeblock-100k grid-aligned}; do
    [ "$scene" = holeblock-1m ] && holeblock_mesh
    [ "$scene" = holeblock-100k ] && holeblock_mesh holeblock-100k 0.34
    log "occlusion/$scene: Monte Carlo light fields first (small scenes only), then every mode"
    "$bin/pnb_bench_occlusion" --scene "$scene" --data-dir "$data" --test-data "$root/tests/data" --frames "$frames" \
      --size "${PNB_BENCH_OCC_SIZE:-512x512}" --grid "${PNB_BENCH_OCC_GRID:-128}" \
      --preillum "${PNB_BENCH_OCC_PREILLUM:-64}" --mc-max-points "${PNB_BENCH_OCC_MC_MAX_POINTS:-60000}" \
      --alpha "${PNB_BENCH_OCC_ALPHA:-1}" --weight "${PNB_BENCH_OCC_WEIGHT:-mean}" \
      --pyramid "${PNB_BENCH_OCC_PYRAMID:-opacity}" --level "${PNB_BENCH_OCC_LEVEL:-continuous}" --gpu "${PNB_BENCH_OCC_GPU:-on}" \
      --modes "${PNB_BENCH_OCC_MODES:-all}"
  done
}

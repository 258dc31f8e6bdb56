# SPDX-License-Identifier: BSD-3-Clause
# usage: gpu     (Penumbra GPU ray caster via headless EGL vs its CPU path vs vtkProjectedTetrahedraMapper, 512x512, ~1M tets)
# Without a GPU the GPU path runs on Mesa's llvmpipe, as VTK does under Xvfb.
# Sourced by bench/run.sh, which provides build_targets, log, holeblock_mesh, $root, $build, $data
# and $frames. Environment: PNB_BENCH_GPU_SCENE (holeblock-1m, the default, or grid-aligned),
# PNB_BENCH_GPU_SIZE (WxH, default the scene's 512x512; smaller for slow software devices),
# PNB_EGL_DEVICE / PNB_EGL_LIBRARY (which EGL device or library the GPU path uses).

bench_gpu() {
  command -v xvfb-run >/dev/null || { log "xvfb-run is missing: run scripts/setup.sh"; exit 1; }
  build_targets pnb_bench_gpu_penumbra pnb_bench_gpu_vtk
  local scene=${PNB_BENCH_GPU_SCENE:-holeblock-1m} bin=$build/bench lines
  local size_args=()
  [ -n "${PNB_BENCH_GPU_SIZE:-}" ] && size_args=(--size "$PNB_BENCH_GPU_SIZE")
  [ "$scene" = holeblock-1m ] && holeblock_mesh
  log "gpu/$scene: penumbra-gpu and penumbra-cpu (the reference image is computed once, then cached)"
  lines=$("$bin/pnb_bench_gpu_penumbra" --scene "$scene" --data-dir "$data" --frames "$frames" "${size_args[@]}")
  # Debian's VTK renders only through X11; the GPU path needs no display.
  log "gpu/$scene: vtk-projected-tetra (under xvfb-run)"
  lines+=$'\n'$(xvfb-run -a -s "-screen 0 1024x1024x24" "$bin/pnb_bench_gpu_vtk" --scene "$scene" \
    --data-dir "$data" --frames "$frames" "${size_args[@]}")
  python3 "$root/bench/gpu/combine.py" <<<"$lines"
}

#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# bench/run.sh NAME -- builds what benchmark NAME needs and runs it, from the repository root.
# Prints one JSON object per line on stdout (build logs and progress go to stderr) and keeps a
# copy in build-bench/NAME.jsonl. Benchmarks:
#   render   Penumbra's CPU ray caster vs VTK 9's unstructured-grid volume mappers (bench/README.md)
# Environment: PNB_BENCH_BUILD_DIR (default build-bench), PNB_BENCH_FRAMES (timed frames, default 5,
# at least 5 for reported numbers), PNB_BENCH_SCENES (default "holeblock-1m grid-aligned"),
# PNB_BENCH_VTK_INTEGRATOR (linear, the default: the integrator matching Penumbra's optical model;
# or default: the one each VTK mapper picks by itself), PNB_BENCH_VTK_RENDERERS (default
# "vtk-raycast,vtk-zsweep"; the z-sweep takes minutes per frame).
set -euo pipefail

usage() {
  echo "usage: bench/run.sh NAME" >&2
  echo "  NAME: render  (Penumbra CPU ray caster vs vtkUnstructuredGridVolumeRayCastMapper and" >&2
  echo "                 vtkUnstructuredGridVolumeZSweepMapper, 512x512, ~1M tets)" >&2
  for f in "${root:-.}"/bench/*/bench.sh; do [ -f "$f" ] && sed -n 's/^# usage: /  /p' "$f" >&2; done
  exit 2
}

[ $# -eq 1 ] || usage
name=$1
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${PNB_BENCH_BUILD_DIR:-$root/build-bench}
data=$build/data
frames=${PNB_BENCH_FRAMES:-5}

log() { echo "bench/run.sh: $*" >&2; }

# Configures (once) and builds the given targets in the benchmark build directory. Tests,
# examples and the VTK adaptor are not needed here.
build_targets() {
  local generator=()
  if [ ! -f "$build/CMakeCache.txt" ] && command -v ninja >/dev/null; then generator=(-G Ninja); fi
  cmake -S "$root" -B "$build" "${generator[@]}" -DCMAKE_BUILD_TYPE=Release -DPNB_BUILD_BENCHMARKS=ON \
    -DPNB_BUILD_TESTS=OFF -DPNB_BUILD_EXAMPLES=OFF -DPNB_ENABLE_VTK=OFF >&2
  cmake --build "$build" --parallel "$(nproc)" --target "$@" >&2
}

# The graded non-convex holeblock of bench/scenes/holeblock.geo (gmsh HXT, as bench/README.md describes):
# holeblock_mesh [NAME H], by default holeblock-1m at h = 0.156 (about 1M tets); holeblock-100k is
# h = 0.34 (about 98K tets). Generated once, then cached in build-bench/data.
holeblock_mesh() {
  local name=${1:-holeblock-1m} h=${2:-0.156}
  local out=$data/$name.vtk
  [ -f "$out" ] && return 0
  command -v gmsh >/dev/null || { log "gmsh is missing: run scripts/setup.sh"; exit 1; }
  mkdir -p "$data"
  log "generating $out with gmsh (up to a minute)"
  gmsh -3 -nt "$(nproc)" -algo hxt -bin -format vtk -setnumber h "$h" -setnumber ratio 20 \
    -o "$data/$name.tmp.vtk" "$root/bench/scenes/holeblock.geo" >"$data/gmsh-$name.log" 2>&1 \
    || { log "gmsh failed, see $data/gmsh-$name.log"; exit 1; }
  mv "$data/$name.tmp.vtk" "$out"
}

bench_render() {
  command -v xvfb-run >/dev/null || { log "xvfb-run is missing: run scripts/setup.sh"; exit 1; }
  build_targets pnb_bench_render_penumbra pnb_bench_render_vtk
  holeblock_mesh
  local bin=$build/bench scene lines
  for scene in ${PNB_BENCH_SCENES:-holeblock-1m grid-aligned}; do
    log "render/$scene: penumbra-cpu (the reference image is computed once, then cached)"
    lines=$("$bin/pnb_bench_render_penumbra" --scene "$scene" --data-dir "$data" --frames "$frames")
    # Debian's VTK renders only through X11; Penumbra needs no display.
    log "render/$scene: vtk-raycast, vtk-zsweep (under xvfb-run; the z-sweep takes about a minute per frame)"
    lines+=$'\n'$(xvfb-run -a -s "-screen 0 1024x1024x24" "$bin/pnb_bench_render_vtk" --scene "$scene" \
      --data-dir "$data" --frames "$frames" --integrator "${PNB_BENCH_VTK_INTEGRATOR:-linear}" \
      --renderers "${PNB_BENCH_VTK_RENDERERS:-vtk-raycast,vtk-zsweep}")
    python3 "$root/bench/render/combine.py" <<<"$lines"
  done
}

# Every other benchmark lives in bench/NAME/bench.sh, which defines bench_NAME using the helpers
# above (build_targets, log, $build, $data, $frames).
if [ "$name" != render ]; then
  [[ "$name" =~ ^[a-z0-9_-]+$ ]] && [ -f "$root/bench/$name/bench.sh" ] \
    || { echo "bench/run.sh: unknown benchmark '$name'" >&2; usage; }
  # shellcheck source=/dev/null
  source "$root/bench/$name/bench.sh"
fi
mkdir -p "$build"
"bench_${name//-/_}" | tee "$build/$name.jsonl"

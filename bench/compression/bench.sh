# SPDX-License-Identifier: BSD-3-Clause
# usage: compression  (Penumbra's time-window VQ vs ZFP, fpzip, temporal delta + zstd: smooth, shock, EEG-like ~100K x 128, and mug.e)
# Sourced by bench/run.sh, which provides build_targets, log, $root, $build and $data.
# Environment: PNB_BENCH_COMPRESSION_FIELDS (default "smooth shock shock-nonuniform eeg mug"),
# PNB_BENCH_COMPRESSION_VERTICES (default 100000), PNB_BENCH_COMPRESSION_STEPS (default 128).

# mug.e's point fields as raw arrays (uint64 n, uint64 steps, f64 times, f32 values), once.
compression_export_mug() {
  local out=$data/compression
  [ -f "$out/mug-convected.f32" ] && return 0
  mkdir -p "$out"
  log "compression: exporting mug.e time steps with python3-vtk9"
  /usr/bin/python3 "$root/bench/compression/export_mug.py" "$root/tests/data/mug.e" "$out" >&2 \
    || { log "exporting mug.e failed (python3-vtk9 missing? run scripts/setup.sh)"; exit 1; }
}

bench_compression() {
  build_targets pnb_bench_compression
  local bin=$build/bench/pnb_bench_compression scratch=$data/compression field
  mkdir -p "$scratch"
  for field in ${PNB_BENCH_COMPRESSION_FIELDS:-smooth shock shock-nonuniform eeg mug}; do
    if [ "$field" = mug ]; then
      compression_export_mug
      for name in convected diffused; do
        log "compression/mug-$name"
        "$bin" --field "raw:$scratch/mug-$name.f32:mug-$name" --scratch "$scratch"
      done
    else
      log "compression/$field"
      "$bin" --field "$field" --vertices "${PNB_BENCH_COMPRESSION_VERTICES:-100000}" \
        --steps "${PNB_BENCH_COMPRESSION_STEPS:-128}" --scratch "$scratch"
    fi
  done
}

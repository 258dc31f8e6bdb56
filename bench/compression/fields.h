// SPDX-License-Identifier: BSD-3-Clause
// bench/compression/fields.h -- the time-varying fields the compression benchmark runs on.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "penumbra/compression/streaming_encoder.h"
#include "penumbra/core/aligned_allocator.h"

namespace pnb_bench {

/// Floats on a 64-byte boundary: every array the benchmark copies or decodes into, so that a
/// memcpy's speed does not depend on where the allocator put source and destination. On mug's
/// 317 KB, memcpy ran at 68-71 GB/s between arrays with the same offset in a cache line and at
/// 45 between arrays 32 bytes apart, and which one a run got changed with the length of the
/// scratch directory's name.
using Floats = std::vector<float, penumbra::AlignedAllocator<float, 64>>;

/// values[t * vertices + v] (step-major, as a solver hands steps over).
struct Field {
  std::string name;
  std::uint64_t vertices = 0;
  std::uint32_t steps = 0;
  std::vector<double> times;
  Floats values;
  double range() const;
};

/// Synthetic fields on `vertices` points in the unit cube, ordered along a Morton curve (so
/// neighbouring indices are neighbours in space, as in a solver's mesh numbering):
///   smooth  six Gaussian blobs advected across the domain, amplitudes breathing slowly
///   shock   a blast-like planar front crossing the domain: a jump of uniform strength that
///           weakens as it travels, exponential relaxation behind, a smooth state ahead
///   shock-nonuniform  a planar front whose jump varies along it (0.5 to 1.5): harder for VQ
///   eeg     eight oscillating sources (8-13 steps per period) with spatial fall-off plus
///           white noise at 30% of the signal: an EEG-like, low-SNR field
Field synthetic_field(const std::string& kind, std::uint64_t vertices, std::uint32_t steps);

/// A field exported by export_mug.py (uint64 vertices, uint64 steps, f64 times, f32 values).
Field load_raw_field(const std::string& path, const std::string& name);

/// The field a `--field` option names: a synthetic kind (with `vertices` and `steps`), or
/// raw:PATH:NAME for load_raw_field.
Field field_from_spec(const std::string& spec, std::uint64_t vertices, std::uint32_t steps);

/// Streams every step of f through a StreamingEncoder into the field file `path`; its stats.
penumbra::compression::StreamingStats write_field_file(const Field& f, const std::string& path,
                                                       const penumbra::compression::CodecParams& codec);

}  // namespace pnb_bench

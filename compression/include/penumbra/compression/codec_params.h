// SPDX-License-Identifier: BSD-3-Clause
// compression/include/penumbra/compression/codec_params.h
#pragma once
#include <cstdint>

#include "penumbra/core/export.h"

PNB_PUBLIC_BEGIN

namespace penumbra::compression {

/// How a maximum error is stated. `range_relative` multiplies the value range of the data
/// seen so far (a streaming encoder does not know the final range), so the bound actually
/// held is never looser than value × final range.
enum class BoundKind : std::uint32_t { none = 0, absolute = 1, range_relative = 2 };

struct ErrorBound {
  BoundKind kind = BoundKind::none;
  double value = 0.0;
};

/// Parameters of the time-window vector-quantisation codec (Bernardon et al., sec. 3).
/// The highest zstd level CodecParams::entropy_level takes.
constexpr int kMaxEntropyLevel = 19;

struct CodecParams {
  /// Time steps per window (= per page). A multiple of 8 in [8, 1024]: D8 holds the means
  /// of 8 equal sub-blocks, D_W the per-step detail.
  std::uint32_t window = 64;
  /// Entries of each codebook, 2..256 (indices are stored as one byte).
  std::uint32_t codebook_size = 256;
  /// Vertices sampled (stratified) to train the codebooks; training cost does not grow
  /// with the mesh beyond this. All vertices are still encoded against the codebooks.
  std::uint32_t training_sample = 8192;
  /// Lloyd iterations after each codebook split (cold start) and from the previous
  /// window's codebooks (warm start).
  std::uint32_t cold_iterations = 8;
  std::uint32_t warm_iterations = 6;
  /// D8 candidates tried per vertex: each is completed by its best D_W entry and the pair
  /// with the least error is kept (1: plain two-stage search; more: better on jumps, slower).
  std::uint32_t search_candidates = 2;
  /// Seed of the sampling and split perturbations; equal seeds give equal files.
  std::uint64_t seed = 1;
  /// Also train a shift-aligned codebook per window (each vertex-window shifted so that its
  /// largest step-to-step change lands at one frame position; see PageMethod::vq_aligned)
  /// and keep it for pages where it represents the training sample better. Helps fields
  /// with moving fronts (a jump at a different step at every vertex); costs training time
  /// (about +40..75% of the plain codebooks' training). Windows up to 256 steps.
  bool aligned = true;
  /// Optional guaranteed maximum error at every value.
  ErrorBound bound;
  /// Without a bound: a window whose VQ signal-to-noise ratio (on the training sample) is
  /// below this is stored with the predictive coder at a bound equal to VQ's RMS error.
  double min_vq_snr_db = 12.0;
  /// Predictive pages in blocks of 16 vertices (PageMethod::predictive_lanes). Off: per-vertex
  /// sections (PageMethod::predictive), as files of format versions 1 and 2 hold them.
  bool predictive_lanes = true;
  /// zstd level of the lossless stage over each page's bytes, 1..19; 0 stores pages as they
  /// are. A page is kept as it is where zstd would not save an eighth of it. Level 3 compresses
  /// at about 250 MB/s of page bytes on the writer's thread and loads undo it at about 1 GB/s.
  int entropy_level = 3;
};

/// How one page is stored; recorded in its header.
enum class PageMethod : std::uint32_t {
  vq = 0,           ///< mean + D8 + D_W codebooks, 4 bytes per vertex
  vq_residual = 1,  ///< vq plus a quantised residual that holds the error bound
  predictive = 2,   ///< error-bounded temporal predictive coder (VQ-poor fields)
  /// Shift-aligned VQ (format version 2): per vertex a 16-bit level, a shift and an index
  /// into a codebook over a frame of 2W-1 steps; the vertex-window is the level plus the
  /// entry's W steps starting at W-1-shift, i.e. the entry's jump at frame position W-1
  /// lands on the vertex's step `shift`. 4 bytes per vertex, codebook stored in 16 bits.
  vq_aligned = 3,
  vq_aligned_residual = 4,  ///< vq_aligned plus a quantised residual that holds the error bound
  /// The predictive coder with its integers in blocks of 16 vertices that share their widths
  /// (format version 3; version 4 adds a width for the steps just after step 1, version 5 one for
  /// step 2 and a transient end per block; LaneBlocks):
  /// smaller than per-vertex sections where a run's first steps jump, and a whole window decodes
  /// several times faster.
  predictive_lanes = 5,
};

const char* to_string(PageMethod method);

}  // namespace penumbra::compression

PNB_PUBLIC_END

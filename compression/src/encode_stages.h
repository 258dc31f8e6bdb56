// SPDX-License-Identifier: BSD-3-Clause
// compression/src/encode_stages.h -- the stages of encode_window (private):
//   scan     value range, non-finite values and per-vertex means   (encode_scan.cpp)
//   sample   a stratified training sample of vertex-windows         (encode_scan.cpp)
//   train    plain and shift-aligned codebooks, warm started        (encode_training.cpp)
//   choose   the page method and its bound                          (encode_choice.cpp)
//   encode   one page encoder per method                            (encode_vq.cpp, encode_aligned.cpp,
//                                                                     encode_predictive.cpp)
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "penumbra/compression/codec_params.h"
#include "penumbra/compression/encoded_page.h"
#include "penumbra/compression/lbg.h"
#include "penumbra/compression/window_codec.h"
#include "vq_value.h"

namespace penumbra::compression::detail {

/// The window being encoded: data[t * n_vertices + v] for the `steps` real steps, read as a
/// series of `width` steps per vertex (the last real step repeated).
struct Window {
  const float* data;
  std::uint64_t n_vertices;
  std::uint32_t steps;  ///< real steps
  std::uint32_t width;  ///< W (padded length)
  std::uint32_t block;  ///< W / 8

  /// Vertex-major copy of vertices [first, first+count), padded to W by repeating the last step.
  void gather(std::uint64_t first, std::uint64_t count, float* out) const {
    for (std::uint32_t t = 0; t < width; ++t) {
      const float* row = data + std::uint64_t(std::min(t, steps - 1)) * n_vertices + first;
      for (std::uint64_t i = 0; i < count; ++i) out[i * width + t] = row[i];
    }
  }
};

/// Values stored in 16 bits over their own range: values[i] = lo + float(q[i]) * scale.
struct Quantised16 {
  float lo = 0, scale = 0;
  std::vector<std::uint16_t> q;
  std::vector<float> values;  ///< dequantised: what the decoder rebuilds

  VertexMeans stored() const { return {lo, scale, q}; }
};

/// Quantises x to 16 bits over [min x, max x]; the encoder goes on with the dequantised values,
/// so that it measures its errors against what the decoder will see.
template <class T>
Quantised16 quantise_16bit(const std::vector<T>& x) {
  Quantised16 out;
  const auto [lo, hi] = std::minmax_element(x.begin(), x.end());
  out.lo = float(*lo);
  out.scale = float((double(*hi) - double(*lo)) / 65535.0);
  out.q.resize(x.size());
  out.values.resize(x.size());
  for (std::size_t i = 0; i < x.size(); ++i) {
    const double q = out.scale > 0 ? std::nearbyint((double(x[i]) - out.lo) / out.scale) : 0.0;
    out.q[i] = std::uint16_t(std::clamp(q, 0.0, 65535.0));
    out.values[i] = dequantise_mean(out.lo, out.scale, out.q[i]);
  }
  return out;
}

// --- scan and sample (encode_scan.cpp) ---

struct WindowScan {
  float value_min = 0, value_max = 0;  ///< over the real steps
  std::vector<double> mean;            ///< of each vertex's padded series
};
/// One parallel pass over the window. Throws Error(invalid_argument) naming the step (counted
/// from `first_step`) and vertex of the first NaN or Inf.
WindowScan scan_window(const Window& win, std::uint64_t first_step);

/// One vertex from each of S equal strata (S = min(vertices, params.training_sample)).
struct TrainingSample {
  std::vector<std::uint64_t> vertices;
  std::vector<float> series;  ///< S x W: the vertices' padded series
  std::vector<float> means;   ///< their dequantised means
  std::uint64_t size() const { return vertices.size(); }
  const float* series_of(std::uint64_t i, std::uint32_t width) const { return series.data() + i * width; }
};
/// Strata offsets are drawn from params.seed and first_step, so that equal seeds give equal files.
TrainingSample draw_training_sample(const Window& win, const std::vector<float>& mean, const CodecParams& params,
                                    std::uint64_t first_step);

// --- plain VQ: mean + D8 + D_W (encode_vq.cpp) ---

/// D8 of each series in x (count x W): the means of 8 equal blocks of (x - m).
void block_means(const Window& win, const float* x, const float* m, std::uint64_t count, float* d8);
/// What the D_W stage must carry: x minus the decoded mean + D8 entry i8 (closed loop), in the
/// decoder's float arithmetic.
void remove_d8(const Window& win, const std::vector<float>& c8, const float* x, const float* m,
               const std::uint8_t* i8, std::uint64_t count, float* r);

struct TrainedPlainCodebooks {
  std::vector<float> c8;  ///< K x 8
  std::vector<float> cw;  ///< K x W
  std::vector<std::uint8_t> i8, iw;  ///< entries of each sample vertex
  double mse = 0;                    ///< per real value, on the sample
};

// --- shift-aligned VQ (encode_aligned.cpp) ---

/// Each vertex-window placed in a frame of 2W-1 positions so that its largest step-to-step
/// change falls at position W-1, with the value just before that change (its level) removed.
/// A front reaching every vertex at a different step then gives the same aligned shape
/// everywhere, which one codebook entry covers instead of one entry per arrival step.
struct AlignedFrames {
  std::uint32_t dim = 0;             ///< 2W - 1
  std::vector<std::uint8_t> shift;   ///< per vertex: the step of its largest change
  Quantised16 level;                 ///< per vertex
  /// Frames (count x dim, zero outside the vertex's steps) and their first covered positions,
  /// of the series x (count x W) of vertices[i], or of first + i where vertices is null.
  void frame(const float* x, const std::uint64_t* vertices, std::uint64_t first, std::uint64_t count,
             std::uint32_t W, std::uint32_t n, std::vector<float>& u, std::vector<std::uint32_t>& offsets) const;
};
AlignedFrames align_window(const Window& win);

struct TrainedAlignedCodebook {
  Quantised16 entries;                     ///< K x dim, stored in 16 bits; encoding uses the stored values
  std::vector<std::uint8_t> sample_index;  ///< entry of each sample vertex
  double mse = 0;                          ///< per real value, on the sample
};

// --- training (encode_training.cpp) ---

struct Training {
  TrainedPlainCodebooks plain;
  bool tried_aligned = false;  ///< frames and aligned were trained
  AlignedFrames frames;
  TrainedAlignedCodebook aligned;
  bool use_aligned = false;  ///< the aligned codebook fits the sample better
  double seconds = 0;        ///< spent in LBG

  double vq_mse() const { return use_aligned ? aligned.mse : plain.mse; }
  /// The decoded VQ series (W values) of sample vertex i, with the codebooks the page uses.
  void sample_series(const Window& win, const TrainingSample& sample, std::uint64_t i, float* out) const;
};
/// Trains the codebooks on the sample, warm from `warm` where it fits, and leaves this window's
/// codebooks in `warm` for the next.
Training train_codebooks(const Window& win, const TrainingSample& sample, const CodecParams& params, WarmStart* warm);

// --- choice (encode_choice.cpp) ---

struct MethodChoice {
  PageMethod method = PageMethod::vq;
  float bound = 0;  ///< what the residual or predictive coder holds (0: none)
  Quantiser quantiser;  ///< step = 2 bound; lo and first_width where the bound is positive
  double snr_db = 0;              ///< VQ's signal-to-noise ratio on the sample
  double vq_estimate = 0, predictive_estimate = 0;  ///< bytes of the page
};
MethodChoice choose_method(const Window& win, const TrainingSample& sample, const Training& training,
                           const CodecParams& params, float value_min, float value_max, float bound_abs);

// --- one page encoder per method family ---

/// vq, vq_residual.
void encode_vq_page(EncodedPage& page, const Window& win, const Quantised16& means, TrainedPlainCodebooks codebooks,
                    const MethodChoice& choice, std::uint32_t search_candidates);
/// vq_aligned, vq_aligned_residual.
void encode_aligned_page(EncodedPage& page, const Window& win, const AlignedFrames& frames,
                         const TrainedAlignedCodebook& codebook, const MethodChoice& choice);
/// predictive: per-vertex sections in bit blocks.
void encode_predictive_page(EncodedPage& page, const Window& win, const MethodChoice& choice);
/// predictive_lanes: the predictive coder in blocks of 16 vertices.
void encode_predictive_lanes_page(EncodedPage& page, const Window& win, const MethodChoice& choice);

}  // namespace penumbra::compression::detail

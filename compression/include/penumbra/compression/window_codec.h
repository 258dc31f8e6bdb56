// compression/include/penumbra/compression/window_codec.h
#pragma once
#include <cstdint>
#include <memory>
#include <vector>

#include "penumbra/compression/codec_params.h"
#include "penumbra/compression/encoded_page.h"

namespace penumbra::compression {

/// Codebooks carried from one window to the next: LBG starts from them (warm start).
struct WarmStart {
  std::vector<float> c8, cw;
  double vq_mse = 0;      ///< their mean squared error per value on their own window's sample
  std::vector<float> ca;  ///< shift-aligned codebook (CodecParams::aligned)
  double ca_mse = 0;      ///< its mean squared error per value on its own window's sample
  bool aligned_page = false;  ///< the previous page used the aligned codebook
  bool empty() const { return c8.empty(); }
};

struct WindowStats {
  double train_seconds = 0;   ///< LBG on the training sample
  double encode_seconds = 0;  ///< whole window, training included
  double sample_snr_db = 0;   ///< VQ signal-to-noise on the training sample
  std::uint64_t vq_bytes_estimate = 0, predictive_bytes_estimate = 0;
};

/// Encodes one window. `steps` is step-major: steps[t * vertex_count + v], t < step_count
/// <= params.window (a shorter, final window is padded by repeating its last step for VQ and
/// decodes to step_count steps). `bound_abs` > 0 holds |x - decoded| <= bound_abs at every
/// value (params.bound is not consulted here; see resolve_bound). Throws Error
/// (invalid_argument) naming the step and vertex of a NaN or Inf value. `warm` (optional)
/// seeds training and receives this window's codebooks.
EncodedPage encode_window(const float* steps, std::uint64_t vertex_count, std::uint32_t step_count,
                          const double* times, std::uint64_t first_step, const CodecParams& params, float bound_abs,
                          WarmStart* warm = nullptr, WindowStats* stats = nullptr);

/// The absolute bound for a window given the value range seen so far (0: no bound).
float resolve_bound(const ErrorBound& bound, float value_min, float value_max);

/// Decodes step `local_step` of the page for all vertices into out[vertex_count]. VQ and
/// residual pages: O(1) per vertex (the residual is one read at the vertex's known section
/// offset and width; patched sections scan at most 15 exception positions). Predictive
/// pages: O(local_step) per vertex; play them back with a StepCursor.
void decode_step(const EncodedPage& page, std::uint32_t local_step, float* out);
/// Sequential one-step decoding. A predictive page stores each value as the error of a
/// prediction from the steps before it, so decode_step costs O(step) per vertex there; a
/// cursor keeps every vertex's last two integers so that reading step t right after step t-1
/// of the same page (playback) costs O(1) per vertex. Any other order, and every other method,
/// decodes as decode_step does. Results are bit-identical to decode_step. Holds the page it
/// follows and 16 bytes per vertex while that page is predictive.
class StepCursor {
public:
  void decode(const std::shared_ptr<const EncodedPage>& page, std::uint32_t local_step, float* out);

private:
  std::shared_ptr<const EncodedPage> m_page;
  std::uint32_t m_step = 0;           ///< the step m_k1 holds
  std::vector<std::int64_t> m_k1, m_k2;  ///< k at m_step and m_step - 1 (raw vertices: unused)
};

/// Decodes the whole window, step-major: out[t * vertex_count + v], t < step_count.
void decode_window(const EncodedPage& page, float* out);
/// Decodes one vertex's step_count values (random access to one vertex-window).
void decode_vertex(const EncodedPage& page, std::uint64_t vertex, float* out);

}  // namespace penumbra::compression

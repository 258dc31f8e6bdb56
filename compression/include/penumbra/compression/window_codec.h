// SPDX-License-Identifier: BSD-3-Clause
// compression/include/penumbra/compression/window_codec.h
#pragma once
#include <cstdint>
#include <memory>
#include <vector>

#include "penumbra/compression/codec_params.h"
#include "penumbra/compression/encoded_page.h"

#include "penumbra/core/export.h"

PNB_PUBLIC_BEGIN

namespace penumbra::compression {

namespace detail {
struct CursorState;
}

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

/// The absolute bound for a window given the value range seen so far (0: no bound), in the
/// units of the values.
double resolve_bound(const ErrorBound& bound, double value_min, double value_max);

/// Decodes step `local_step` of the page for all vertices into out[vertex_count]. VQ and
/// residual pages: O(1) per vertex (the residual is one read at the vertex's known section
/// offset and width; patched sections scan at most 15 exception positions). Predictive
/// pages: O(local_step) per vertex; play them back with a StepCursor.
void decode_step(const EncodedPage& page, std::uint32_t local_step, float* out);
/// Sequential one-step decoding. A predictive page stores each value as the error of a
/// prediction from the steps before it, so decode_step costs O(step) per vertex there; and a
/// patched section (a few outliers stored apart) is scanned for the step's exception. A cursor
/// keeps, per vertex, the last two integers of a predictive page, where its values start and
/// the position of its next exception, so that reading step t right after step t-1 of the same
/// page (playback) costs O(1) per vertex for every page with bit blocks (residual or
/// predictive). Any other order, and pages without bit blocks, decode as decode_step does.
/// Results are bit-identical to decode_step. Holds the page it follows and, while that page
/// has bit blocks, 13 bytes per vertex (22 on a predictive page).
class StepCursor {
public:
  StepCursor();
  ~StepCursor();
  StepCursor(StepCursor&&) noexcept;
  StepCursor& operator=(StepCursor&&) noexcept;
  void decode(const std::shared_ptr<const EncodedPage>& page, std::uint32_t local_step, float* out);
  /// Lets go of the page it holds, keeping its own memory for the next; the next decode starts
  /// afresh. A pager calls it when playback leaves a page, so that the page's memory can serve
  /// the next load.
  void release() { m_page.reset(); }

private:
  std::shared_ptr<const EncodedPage> m_page;
  std::uint32_t m_step = 0;  ///< the step last decoded from m_page
  std::unique_ptr<detail::CursorState> m_state;
};

/// Whether the decoders may run 8 vertices per vector lane block (AVX2, where the CPU has it)
/// for residual and predictive pages. On by default; results are bit-identical either
/// way, so turning it off only serves to check that and to measure the gain. Process-wide.
void set_vector_decode(bool enabled);
/// True when the vector decoders run (the CPU has AVX2 and set_vector_decode left them on).
bool vector_decode_active();

/// Checks a page value by value: its shape (every array the size its method needs), times for
/// each step, codebook indices and shifts in range, and bit blocks whose every section parses
/// inside its group and starts where section_bits says. Throws Error(invalid_argument) naming
/// the first fault. O(vertices + bits). The decoders check only a page's shape, in O(1), since
/// they run per step; pages from encode_window and from a file (parsed with this same check)
/// need nothing more, but a page assembled or edited by hand must pass this before it is
/// decoded, or a wrong index reads outside the codebooks. FieldWriter::write_page runs it.
void validate_page(const EncodedPage& page);

/// Decodes the whole window, step-major: out[t * vertex_count + v], t < step_count.
void decode_window(const EncodedPage& page, float* out);
/// Decodes one vertex's step_count values (random access to one vertex-window).
void decode_vertex(const EncodedPage& page, std::uint64_t vertex, float* out);

}  // namespace penumbra::compression

PNB_PUBLIC_END

// compression/src/window_decoder.cpp -- decodes a page: one step, the whole window, or one vertex.
#include <algorithm>
#include <string>
#include <vector>

#include "bit_io.h"
#include "predictive_layout.h"
#include "vertex_section.h"
#include "penumbra/compression/window_codec.h"
#include "penumbra/core/error.h"
#include "penumbra/core/thread_pool.h"
#include "vq_value.h"

namespace penumbra::compression {

namespace {

constexpr std::uint64_t kGroup = BitBlocks::kGroupSize;
// Vertices per parallel chunk of a one-step decode: below a few hundred thousand vertices
// starting threads costs more than the decode (about 1 ns per vertex) itself.
constexpr std::size_t kStepChunk = 1 << 18;

bool is_vq(const EncodedPage& p) { return p.method != PageMethod::predictive; }

// Column t of both codebooks: the 2 x K floats a one-step decode looks up.
void step_tables(const EncodedPage& p, std::uint32_t t, std::vector<float>& t8, std::vector<float>& tw) {
  const std::uint32_t K = p.codebook_size, block = p.window / 8;
  t8.resize(K);
  tw.resize(K);
  for (std::uint32_t e = 0; e < K; ++e) {
    t8[e] = p.c8[std::size_t(e) * 8 + t / block];
    tw[e] = p.cw[std::size_t(e) * p.window + t];
  }
}

// One step of the VQ part for vertices [b, e): the hot loop of a one-step decode.
__attribute__((target_clones("avx2", "default"))) void vq_base_range(const EncodedPage& p, const float* t8,
                                                                    const float* tw, std::uint64_t b,
                                                                    std::uint64_t e, float* out) {
  const float lo = p.mean_lo, scale = p.mean_scale;
  const std::uint16_t* mq = p.mean_q.data();
  const std::uint8_t* i8 = p.i8.data();
  const std::uint8_t* iw = p.iw.data();
  for (std::uint64_t v = b; v < e; ++v)
    out[v] = detail::vq_value(detail::dequantise_mean(lo, scale, mq[v]), t8[i8[v]], tw[iw[v]]);
}

constexpr std::uint64_t kNoLimit = ~0ull;

void mean_plus_d8(const EncodedPage& p, const float* t8, std::uint64_t b, std::uint64_t e, float* base) {
  for (std::uint64_t v = b; v < e; ++v)
    base[v - b] = detail::dequantise_mean(p.mean_lo, p.mean_scale, p.mean_q[v]) + t8[p.i8[v]];
}

// out[i] = base[i] + tw[iw[i]]: the hot loop of a full-window decode (AVX2 gathers if present).
__attribute__((target_clones("avx2", "default"))) void add_dw(const float* tw, const std::uint8_t* iw,
                                                                 const float* base, std::uint64_t count, float* out) {
  for (std::uint64_t i = 0; i < count; ++i) out[i] = base[i] + tw[iw[i]];
}

// Value of step t for a vertex whose section was parsed (vq_residual: added to out).
float section_step(const EncodedPage& p, const std::uint8_t* data, const detail::VertexSection& s, std::uint32_t t,
                   float current) {
  if (s.code == BitBlocks::kRawWidth) return detail::bits_float(detail::read_bits(data, s.start + 32ull * t, 32));
  if (p.method == PageMethod::predictive) {
    std::int64_t k = std::int64_t(s.first_value), k2 = k;
    for (std::uint32_t i = 1; i <= t; ++i) {
      const std::int64_t next = detail::predict(s.predictor, i, k, k2) +
                                detail::unzigzag(detail::value_at(data, s.values, p.step_count - 1, i - 1));
      k2 = k;
      k = next;
    }
    return p.lo + float(k) * p.step;
  }
  if (s.values.width == 0 && s.values.exceptions == 0) return current;
  return current + float(detail::unzigzag(detail::value_at(data, s.values, p.step_count, t))) * p.step;
}

// Adds the residual of step t (vq_residual) or writes the value (predictive) for one group.
void blocks_step_group(const EncodedPage& p, std::uint64_t g, std::uint32_t t, float* out) {
  const std::uint64_t first = g * kGroup, last = std::min(p.vertex_count, first + kGroup);
  const std::uint8_t* data = p.blocks.payload.data();
  std::uint64_t pos = p.blocks.group_offsets[g] * 8;
  detail::VertexSection s;
  for (std::uint64_t v = first; v < last; ++v) {
    detail::parse_vertex(p, data, pos, p.blocks.width(v), kNoLimit, s);
    out[v] = section_step(p, data, s, t, out[v]);
    pos = s.end;
  }
}

// All steps of one vertex from its section; `out` holds the VQ base (vq_residual), stride apart.
void section_all(const EncodedPage& p, const std::uint8_t* data, const detail::VertexSection& s, float* out,
                 std::uint64_t stride, std::uint32_t* scratch) {
  const std::uint32_t n = p.step_count;
  if (s.code == BitBlocks::kRawWidth) {
    for (std::uint32_t t = 0; t < n; ++t)
      out[t * stride] = detail::bits_float(detail::read_bits(data, s.start + 32ull * t, 32));
  } else if (p.method == PageMethod::predictive) {
    detail::all_values(data, s.values, n - 1, scratch);
    std::int64_t k = std::int64_t(s.first_value), k2 = k;
    out[0] = p.lo + float(k) * p.step;
    for (std::uint32_t t = 1; t < n; ++t) {
      const std::int64_t next = detail::predict(s.predictor, t, k, k2) + detail::unzigzag(scratch[t - 1]);
      k2 = k;
      k = next;
      out[t * stride] = p.lo + float(k) * p.step;
    }
  } else if (s.values.width || s.values.exceptions) {
    detail::all_values(data, s.values, n, scratch);
    for (std::uint32_t t = 0; t < n; ++t)
      out[t * stride] = out[t * stride] + float(detail::unzigzag(scratch[t])) * p.step;
  }
}

}  // namespace

void decode_step(const EncodedPage& p, std::uint32_t t, float* out) {
  require(out != nullptr, "decode_step: null output");
  require(t < p.step_count, "decode_step: step " + std::to_string(t) + " is outside the page's " +
                                std::to_string(p.step_count) + " steps");
  const std::uint64_t N = p.vertex_count;
  if (is_vq(p)) {
    std::vector<float> t8, tw;
    step_tables(p, t, t8, tw);
    parallel_for(N, kStepChunk, [&](std::size_t b, std::size_t e) { vq_base_range(p, t8.data(), tw.data(), b, e, out); });
  }
  if (p.method != PageMethod::vq) {
    const std::uint64_t groups = (N + kGroup - 1) / kGroup;
    parallel_for(groups, 64, [&](std::size_t b, std::size_t e) {
      for (std::size_t g = b; g < e; ++g) blocks_step_group(p, g, t, out);
    });
  }
}

void decode_window(const EncodedPage& p, float* out) {
  require(out != nullptr, "decode_window: null output");
  const std::uint64_t N = p.vertex_count;
  const std::uint32_t n = p.step_count;
  // Chunks of whole groups: each writes its vertex range of every step row.
  constexpr std::uint64_t kChunk = kGroup * 64;
  std::vector<float> tables;
  if (is_vq(p)) {
    // Both codebook columns of every step, computed once: 2 x K floats per step.
    tables.resize(std::size_t(n) * 2 * p.codebook_size);
    std::vector<float> t8, tw;
    for (std::uint32_t t = 0; t < n; ++t) {
      step_tables(p, t, t8, tw);
      std::copy(t8.begin(), t8.end(), tables.begin() + std::size_t(t) * 2 * p.codebook_size);
      std::copy(tw.begin(), tw.end(), tables.begin() + (std::size_t(t) * 2 + 1) * p.codebook_size);
    }
  }
  parallel_for(N, kChunk, [&](std::size_t b, std::size_t e) {
    if (is_vq(p)) {
      // mean + D8 is constant over each of the 8 blocks of steps: computed once per block,
      // then each step adds one D_W lookup (same float operations as vq_value).
      thread_local std::vector<float> base;
      base.resize(e - b);
      const std::uint32_t block = p.window / 8;
      for (std::uint32_t t = 0; t < n; ++t) {
        const float* t8 = tables.data() + std::size_t(t) * 2 * p.codebook_size;
        if (t % block == 0) mean_plus_d8(p, t8, b, e, base.data());
        add_dw(t8 + p.codebook_size, p.iw.data() + b, base.data(), e - b, out + std::uint64_t(t) * N + b);
      }
    }
    if (p.method == PageMethod::vq) return;
    std::vector<std::uint32_t> scratch(n);
    detail::VertexSection s;
    for (std::uint64_t g = b / kGroup; g * kGroup < e; ++g) {
      std::uint64_t pos = p.blocks.group_offsets[g] * 8;
      const std::uint64_t last = std::min(N, (g + 1) * kGroup);
      for (std::uint64_t v = g * kGroup; v < last; ++v) {
        detail::parse_vertex(p, p.blocks.payload.data(), pos, p.blocks.width(v), kNoLimit, s);
        section_all(p, p.blocks.payload.data(), s, out + v, N, scratch.data());
        pos = s.end;
      }
    }
  });
}

void decode_vertex(const EncodedPage& p, std::uint64_t v, float* out) {
  require(out != nullptr, "decode_vertex: null output");
  require(v < p.vertex_count, "decode_vertex: vertex " + std::to_string(v) + " is outside the page's " +
                                  std::to_string(p.vertex_count) + " vertices");
  if (is_vq(p)) {
    std::vector<float> series(p.window);
    detail::vq_series(detail::dequantise_mean(p.mean_lo, p.mean_scale, p.mean_q[v]), p.c8.data() + std::size_t(p.i8[v]) * 8,
                      p.cw.data() + std::size_t(p.iw[v]) * p.window, p.window, series.data());
    std::copy(series.begin(), series.begin() + p.step_count, out);
  }
  if (p.method == PageMethod::vq) return;
  const std::uint64_t g = v / kGroup;
  std::uint64_t pos = p.blocks.group_offsets[g] * 8;
  detail::VertexSection s;
  for (std::uint64_t u = g * kGroup; u < v; ++u) {
    detail::parse_vertex(p, p.blocks.payload.data(), pos, p.blocks.width(u), kNoLimit, s);
    pos = s.end;
  }
  std::vector<std::uint32_t> scratch(p.step_count);
  detail::parse_vertex(p, p.blocks.payload.data(), pos, p.blocks.width(v), kNoLimit, s);
  section_all(p, p.blocks.payload.data(), s, out, 1, scratch.data());
}

}  // namespace penumbra::compression

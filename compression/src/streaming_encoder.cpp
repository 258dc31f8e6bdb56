// SPDX-License-Identifier: BSD-3-Clause
// compression/src/streaming_encoder.cpp -- in-situ encoder: window buffers + background thread.
#include "penumbra/compression/streaming_encoder.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <string>
#include <utility>

#include "huge_pages.h"
#include "page_coding.h"
#include "page_methods.h"
#include "penumbra/core/error.h"

namespace penumbra::compression {

std::uint64_t StreamingEncoder::required_budget(std::uint64_t n, const CodecParams& c, std::uint32_t buffers) {
  const std::uint64_t window = n * c.window * 4;
  // Per vertex: double mean, float mean, 16-bit mean, two indices, residual bits (about one
  // byte per step at worst before the raw escape, counted at 2 here); per sample vertex: the
  // series and its closed-loop residual; two codebooks.
  const std::uint64_t sample = std::min<std::uint64_t>(n, c.training_sample);
  std::uint64_t working = n * (8 + 4 + 4 + 2ull * c.window) + sample * c.window * 4 * 2 +
                          std::uint64_t(c.codebook_size) * (c.window + 8) * 4 * 2;
  // Section offsets of a page with bit blocks (4 bytes per vertex), and the page's bytes once
  // more while the writer codes them (page_coding.h), as large as its residual bits.
  working += n * 4 + (c.entropy_level > 0 ? n * 2ull * c.window : 0);
  if (c.aligned && c.window <= detail::kMaxAlignedWindow) {
    // Shift-aligned stage: per vertex shift, level (float, 16-bit, dequantised) and index;
    // the sample's frames of 2W-1 values (all, and the half it trains on); the aligned
    // codebook as trained, stored and dequantised, twice when a cold start is tried as well.
    const std::uint64_t frame = 2ull * c.window - 1;
    working += n * (1 + 4 + 2 + 4 + 1) + sample * frame * 4 * 3 / 2 + std::uint64_t(c.codebook_size) * frame * 10 * 2;
  }
  return buffers * window + working;
}

StreamingEncoder::StreamingEncoder(StreamingOptions options) : m_options(std::move(options)) {
  const CodecParams& c = m_options.codec;
  require(m_options.vertex_count >= 1, "StreamingEncoder: vertex_count must be positive");
  require(detail::valid_window(c.window),
          "StreamingEncoder: window must be a multiple of 8 in [8, 1024], got " + std::to_string(c.window));
  require(detail::valid_codebook_size(c.codebook_size),
          "StreamingEncoder: codebook_size must be 2..256, got " + std::to_string(c.codebook_size));
  require(c.bound.kind == BoundKind::none || (std::isfinite(c.bound.value) && c.bound.value > 0),
          "StreamingEncoder: error bound must be positive and finite");
  require(detail::valid_entropy_level(c.entropy_level),
          "StreamingEncoder: entropy_level must be 0.." + std::to_string(kMaxEntropyLevel) + ", got " +
              std::to_string(c.entropy_level));
  const std::uint64_t budget = m_options.memory_budget_bytes;
  std::uint32_t buffers = 2;
  if (budget != 0 && budget < required_budget(m_options.vertex_count, c, 2)) {
    buffers = 1;
    if (budget < required_budget(m_options.vertex_count, c, 1))
      throw Error(ErrorCode::invalid_argument,
                  "StreamingEncoder: memory budget of " + std::to_string(budget) + " bytes cannot hold one window of " +
                      std::to_string(c.window) + " steps x " + std::to_string(m_options.vertex_count) +
                      " vertices (needs " + std::to_string(required_budget(m_options.vertex_count, c, 1)) +
                      " bytes); raise the budget or shorten the window");
  }
  m_stats.buffers = buffers;
  // Left unwritten until push fills them: zeroing (and copying) gigabytes here held the solver
  // up for seconds at millions of vertices, one first touch of each page at a time.
  for (std::uint32_t b = 0; b < buffers; ++b)
    m_buffers.push_back(detail::uninitialised_on_huge_pages<float>(m_options.vertex_count * c.window));
  m_busy.assign(buffers, false);
  FieldInfo info;
  info.name = m_options.field_name;
  info.vertex_count = m_options.vertex_count;
  info.window = c.window;
  info.codebook_size = c.codebook_size;
  info.bound = c.bound;
  m_writer = std::make_unique<FieldWriter>(m_options.path, info, c.entropy_level);
  m_thread = std::thread([this] { worker_loop(); });
}

StreamingEncoder::~StreamingEncoder() {
  {
    std::lock_guard<std::mutex> lock(m_mutex);
    m_stop = true;
  }
  m_wake.notify_all();
  if (m_thread.joinable()) m_thread.join();
}

void StreamingEncoder::rethrow_locked() {
  if (m_error) std::rethrow_exception(m_error);
}

void StreamingEncoder::wait_buffer_free(std::size_t buffer, bool count_as_solver_wait) {
  std::unique_lock<std::mutex> lock(m_mutex);
  rethrow_locked();
  if (!m_busy[buffer]) return;
  const auto start = std::chrono::steady_clock::now();
  m_done.wait(lock, [&] { return !m_busy[buffer] || m_error; });
  if (count_as_solver_wait) {
    ++m_stats.solver_waits;
    m_stats.solver_wait_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
  rethrow_locked();
}

namespace {

[[noreturn]] void refuse_value(std::uint64_t step, double time, std::uint64_t vertex, const std::string& what) {
  throw Error(ErrorCode::invalid_argument, "StreamingEncoder::push: step " + std::to_string(step) + " (time " +
                                               std::to_string(time) + "), vertex " + std::to_string(vertex) + " " +
                                               what + "; the step was not recorded");
}

// The finite range of one step's values; refuses the step at its first NaN or Inf.
template <class T>
std::pair<double, double> step_range(const T* values, std::uint64_t count, std::uint64_t step, double time) {
  double lo = double(values[0]), hi = lo;
  for (std::uint64_t v = 0; v < count; ++v) {
    const double x = double(values[v]);
    if (!std::isfinite(x)) refuse_value(step, time, v, std::string("is ") + (std::isnan(x) ? "NaN" : "infinite"));
    lo = std::min(lo, x);
    hi = std::max(hi, x);
  }
  return {lo, hi};
}

// Rounds a bound in stored units down to float32, within float32's positive normal range.
float stored_bound(double bound) {
  float b = float(std::min(bound, double(std::numeric_limits<float>::max())));
  if (double(b) > bound) b = std::nextafter(b, 0.f);
  return std::max(b, std::numeric_limits<float>::min());
}

}  // namespace

float* StreamingEncoder::next_step_slot() {
  if (m_filled == 0) wait_buffer_free(m_filling, true);
  else {
    std::lock_guard<std::mutex> lock(m_mutex);
    rethrow_locked();
  }
  return m_buffers[m_filling].get() + std::uint64_t(m_filled) * m_options.vertex_count;
}

void StreamingEncoder::commit_step(double time, double lo, double hi) {
  if (m_step == 0) m_min = lo, m_max = hi;
  m_min = std::min(m_min, lo);
  m_max = std::max(m_max, hi);
  m_times.push_back(time);
  ++m_filled;
  ++m_step;
  if (m_filled == m_options.codec.window) submit(m_filled);
}

std::pair<double, double> StreamingEncoder::range_with(double lo, double hi) const {
  return m_step == 0 ? std::pair{lo, hi} : std::pair{std::min(m_min, lo), std::max(m_max, hi)};
}

void StreamingEncoder::push(double time, const float* values) {
  if (m_finished) throw Error(ErrorCode::invalid_operation, "StreamingEncoder::push: already finished");
  require(values != nullptr, "StreamingEncoder::push: null values");
  const std::uint64_t N = m_options.vertex_count;
  // Reject bad values here, on the solver's thread, before anything is recorded.
  const auto [lo, hi] = step_range(values, N, m_step, time);
  if (!m_map.identity()) {  // a window begun in double goes on in its map
    const std::vector<double> wide(values, values + N);
    push(time, wide.data());
    return;
  }
  std::memcpy(next_step_slot(), values, N * 4);
  m_reach = std::max({m_reach, std::fabs(lo), std::fabs(hi)});
  commit_step(time, lo, hi);
}

void StreamingEncoder::push(double time, const double* values) {
  if (m_finished) throw Error(ErrorCode::invalid_operation, "StreamingEncoder::push: already finished");
  require(values != nullptr, "StreamingEncoder::push: null values");
  const std::uint64_t N = m_options.vertex_count;
  const auto [lo, hi] = step_range(values, N, m_step, time);
  const ValueMap map = m_filled == 0 ? ValueMap::fit(values, N) : m_map;
  // What float32 may cost before the codec: half the bound, leaving it the other half; without a
  // bound, a tenth of what the VQ codec itself costs on smooth fields.
  const auto [seen_lo, seen_hi] = range_with(lo, hi);
  const double bound = resolve_bound(m_options.codec.bound, seen_lo, seen_hi);
  const double range = 2 * (seen_hi / 2 - seen_lo / 2);
  const double allowed = bound > 0 ? bound / 2 : 1e-4 * range;
  float* slot = next_step_slot();
  double worst = 0, reach = 0;
  for (std::uint64_t v = 0; v < N; ++v) {
    const float x = map.stored(values[v]);
    const double moved = std::fabs(values[v] - map.value(x));
    if (!std::isfinite(x) || (moved > allowed && range > 0)) {
      char text[320];
      if (!std::isfinite(x))
        std::snprintf(text, sizeof text, "has the value %.17g, beyond float32's range around its window's reference %.17g (scale %.3g)",
                      values[v], map.offset, map.scale);
      else
        std::snprintf(text, sizeof text,
                      "has the value %.17g, which float32 around its window's reference %.17g moves by %.3g while the values vary by %.3g, "
                      "beyond the %.3g it may lose (%s): the field drifted too far within one window; shorten the window",
                      values[v], map.offset, moved, range, allowed, bound > 0 ? "half the error bound" : "1e-4 of the range without an error bound");
      refuse_value(m_step, time, v, text);
    }
    slot[v] = x;
    worst = std::max(worst, moved);
    reach = std::max(reach, double(std::fabs(x)));
  }
  m_map = map;
  m_narrowing = std::max(m_narrowing, worst);
  m_reach = std::max(m_reach, reach);
  commit_step(time, lo, hi);
}

void StreamingEncoder::submit(std::uint32_t steps) {
  // The codec holds its bound on the stored values; in the field's units that bound is what is
  // left of the field's bound after float32's narrowing and the map's own rounding.
  float bound = 0;
  if (const double b = resolve_bound(m_options.codec.bound, m_min, m_max); b > 0) {
    const double rounding = m_map.identity() ? 0 : 4 * std::numeric_limits<double>::epsilon() * (std::fabs(m_map.offset) + m_map.scale * m_reach);
    bound = stored_bound((b - m_narrowing - rounding) / m_map.scale);
  }
  Job job{m_filling, steps, m_step - steps, m_times, m_map, bound};
  {
    std::lock_guard<std::mutex> lock(m_mutex);
    m_busy[m_filling] = true;
    m_jobs.push_back(std::move(job));
  }
  m_wake.notify_all();
  m_times.clear();
  m_filled = 0;
  m_map = ValueMap{}, m_narrowing = 0, m_reach = 0;  // the next window starts afresh
  m_filling = (m_filling + 1) % m_buffers.size();
}

void StreamingEncoder::worker_loop() {
  // The window buffers' memory is faulted in here, while the solver fills the first window, so
  // that its pushes do not each stop for the kernel's first touch of their pages (2M vertices:
  // 26-32 ms per push over the first two windows, against 8 once the pages are there). Only
  // while idle: once a window is submitted (full, or the last at finish) its encoding comes first.
  const std::uint64_t bytes = m_options.vertex_count * m_options.codec.window * 4;
  for (const auto& buffer : m_buffers)
    if (!detail::populate_for_writing(buffer.get(), bytes, std::size_t(32) << 20, [&] {
          std::lock_guard<std::mutex> idle(m_mutex);
          return !m_stop && m_jobs.empty();
        }))
      break;
  std::unique_lock<std::mutex> lock(m_mutex);
  while (true) {
    m_wake.wait(lock, [&] { return m_stop || !m_jobs.empty(); });
    if (m_jobs.empty()) return;  // stop requested and nothing left
    Job job = std::move(m_jobs.front());
    m_jobs.erase(m_jobs.begin());
    lock.unlock();
    try {
      if (!m_error) {
        WindowStats ws;
        auto page = encode_window(m_buffers[job.buffer].get(), m_options.vertex_count, job.steps,
                                  job.times.data(), job.first_step, m_options.codec, job.bound, &m_warm, &ws);
        page.map = job.map;
        m_writer->write_page(page);
        lock.lock();
        m_stats.pages++;
        m_stats.steps += job.steps;
        m_stats.bytes_written = m_writer->bytes_written();
        m_stats.encode_seconds += ws.encode_seconds;
        m_stats.max_train_seconds = std::max(m_stats.max_train_seconds, ws.train_seconds);
        m_stats.methods.push_back(page.method);
        lock.unlock();
      }
    } catch (...) {
      lock.lock();
      m_error = std::current_exception();
      lock.unlock();
    }
    lock.lock();
    m_busy[job.buffer] = false;
    m_done.notify_all();
  }
}

void StreamingEncoder::finish() {
  if (m_finished) return;
  if (m_filled > 0) submit(m_filled);
  for (std::size_t b = 0; b < m_buffers.size(); ++b) wait_buffer_free(b, false);
  {
    std::lock_guard<std::mutex> lock(m_mutex);
    rethrow_locked();
  }
  m_writer->finish();
  m_finished = true;
  std::lock_guard<std::mutex> lock(m_mutex);
  m_stats.bytes_written = m_writer->bytes_written();
}

StreamingStats StreamingEncoder::stats() const {
  std::lock_guard<std::mutex> lock(m_mutex);
  return m_stats;
}

}  // namespace penumbra::compression

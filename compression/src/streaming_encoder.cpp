// SPDX-License-Identifier: BSD-3-Clause
// compression/src/streaming_encoder.cpp -- in-situ encoder: window buffers + background thread.
#include "penumbra/compression/streaming_encoder.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>

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

void StreamingEncoder::push(double time, const float* values) {
  if (m_finished) throw Error(ErrorCode::invalid_operation, "StreamingEncoder::push: already finished");
  require(values != nullptr, "StreamingEncoder::push: null values");
  const std::uint64_t N = m_options.vertex_count;
  // Reject bad values here, on the solver's thread, before anything is recorded.
  float lo = values[0], hi = values[0];
  for (std::uint64_t v = 0; v < N; ++v) {
    const float x = values[v];
    if (!std::isfinite(x))
      throw Error(ErrorCode::invalid_argument, "StreamingEncoder::push: step " + std::to_string(m_step) +
                                                   " (time " + std::to_string(time) + "), vertex " + std::to_string(v) +
                                                   " is " + (std::isnan(x) ? "NaN" : "infinite") +
                                                   "; the step was not recorded");
    lo = std::min(lo, x);
    hi = std::max(hi, x);
  }
  if (m_filled == 0) wait_buffer_free(m_filling, true);
  else {
    std::lock_guard<std::mutex> lock(m_mutex);
    rethrow_locked();
  }
  std::memcpy(m_buffers[m_filling].get() + std::uint64_t(m_filled) * N, values, N * 4);
  if (m_step == 0) m_min = lo, m_max = hi;
  m_min = std::min(m_min, lo);
  m_max = std::max(m_max, hi);
  m_times.push_back(time);
  ++m_filled;
  ++m_step;
  if (m_filled == m_options.codec.window) submit(m_filled);
}

void StreamingEncoder::submit(std::uint32_t steps) {
  Job job{m_filling, steps, m_step - steps, m_times, resolve_bound(m_options.codec.bound, m_min, m_max)};
  {
    std::lock_guard<std::mutex> lock(m_mutex);
    m_busy[m_filling] = true;
    m_jobs.push_back(std::move(job));
  }
  m_wake.notify_all();
  m_times.clear();
  m_filled = 0;
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
        const auto page = encode_window(m_buffers[job.buffer].get(), m_options.vertex_count, job.steps,
                                        job.times.data(), job.first_step, m_options.codec, job.bound, &m_warm, &ws);
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

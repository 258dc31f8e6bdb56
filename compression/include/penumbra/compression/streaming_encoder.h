// SPDX-License-Identifier: BSD-3-Clause
// compression/include/penumbra/compression/streaming_encoder.h
#pragma once
#include <condition_variable>
#include <cstdint>
#include <exception>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "penumbra/compression/codec_params.h"
#include "penumbra/compression/field_file.h"
#include "penumbra/compression/value_map.h"
#include "penumbra/compression/window_codec.h"

#include "penumbra/core/export.h"

PNB_PUBLIC_BEGIN

namespace penumbra::compression {

struct StreamingOptions {
  std::string path;        ///< final file; written as path + ".partial" until finish()
  std::string field_name;
  std::uint64_t vertex_count = 0;
  CodecParams codec;
  /// Bytes the encoder may hold: window buffers plus working memory. With room for two
  /// windows the solver fills one while the other is encoded; with room for one it waits
  /// for the encoder at each window boundary (counted). 0: as much as two windows need.
  std::uint64_t memory_budget_bytes = 0;
};

struct StreamingStats {
  std::uint64_t steps = 0, pages = 0, bytes_written = 0;
  std::uint64_t solver_waits = 0;   ///< push calls that waited for the encoder (finish always waits)
  double solver_wait_seconds = 0;
  double encode_seconds = 0;        ///< background time, all windows
  double max_train_seconds = 0;     ///< slowest LBG training of one window
  std::uint32_t buffers = 0;        ///< window buffers the budget allowed (1 or 2)
  std::vector<PageMethod> methods;  ///< how each page was stored
};

/// Compresses a field as a solver produces it: push() copies one step into the current
/// window buffer; a full window is encoded and written on a background thread while the
/// solver goes on; finish() encodes the final (possibly partial) window and completes the
/// file. Errors from the background thread are rethrown by the next push() or finish().
class StreamingEncoder {
public:
  explicit StreamingEncoder(StreamingOptions options);
  /// Without finish(): waits for the window being encoded, then leaves path + ".partial"
  /// holding every finished page (readable with OpenOptions::recover_incomplete).
  ~StreamingEncoder();
  StreamingEncoder(const StreamingEncoder&) = delete;
  StreamingEncoder& operator=(const StreamingEncoder&) = delete;

  /// Adds the next time step (vertex_count values). Throws Error(invalid_argument) naming
  /// the vertex of a NaN/Inf value; that step is then not recorded.
  void push(double time, const float* values);
  /// The same for values in double: each window stores them through a ValueMap fitted to its
  /// first step, so that any finite field keeps its variation (and the error bound holds in the
  /// field's units) whatever its magnitude or offset. A later step of the window that drifted so
  /// far from the first that float32 in that map moves a value by more than half the error bound
  /// (without a bound: 1e-4 of the range seen so far) is refused with Error(invalid_argument)
  /// naming the step, the vertex and both amounts, and not recorded.
  void push(double time, const double* values);
  void finish();
  StreamingStats stats() const;

  /// Smallest budget that holds `buffers` window buffers plus the encoder's working memory.
  static std::uint64_t required_budget(std::uint64_t vertex_count, const CodecParams& codec, std::uint32_t buffers);

private:
  struct Job {
    std::size_t buffer;
    std::uint32_t steps;
    std::uint64_t first_step;
    std::vector<double> times;
    ValueMap map;
    float bound;  ///< in stored units
  };
  void worker_loop();
  void submit(std::uint32_t steps);
  /// Waits until the window buffer being filled may take the next step; returns where it goes.
  float* next_step_slot();
  /// Counts a step whose values are in the buffer, with their range; submits a full window.
  void commit_step(double time, double lo, double hi);
  /// The range of the values seen so far together with a step's [lo, hi].
  std::pair<double, double> range_with(double lo, double hi) const;
  void wait_buffer_free(std::size_t buffer, bool count_as_solver_wait);
  void rethrow_locked();

  StreamingOptions m_options;
  std::unique_ptr<FieldWriter> m_writer;
  std::vector<std::unique_ptr<float[]>> m_buffers;  // vertex_count x window each, uninitialised
  std::vector<bool> m_busy;
  std::size_t m_filling = 0;
  std::uint32_t m_filled = 0;
  std::uint64_t m_step = 0;
  std::vector<double> m_times;
  double m_min = 0, m_max = 0;  ///< of the values pushed, in the field's units
  ValueMap m_map;               ///< of the window being filled
  double m_narrowing = 0;       ///< the most float32 moved a value of that window, in the field's units
  double m_reach = 0;           ///< the largest |stored value| of that window
  bool m_finished = false;

  mutable std::mutex m_mutex;
  std::condition_variable m_wake, m_done;
  std::vector<Job> m_jobs;
  bool m_stop = false;
  std::exception_ptr m_error;
  StreamingStats m_stats;
  WarmStart m_warm;
  std::thread m_thread;
};

}  // namespace penumbra::compression

PNB_PUBLIC_END

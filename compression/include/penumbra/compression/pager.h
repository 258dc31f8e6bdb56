// SPDX-License-Identifier: BSD-3-Clause
// compression/include/penumbra/compression/pager.h
#pragma once
#include <condition_variable>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include "penumbra/compression/field_file.h"
#include "penumbra/compression/window_codec.h"

#include "penumbra/core/export.h"

PNB_PUBLIC_BEGIN

namespace penumbra::compression {

struct PagerOptions {
  /// Most bytes of loaded pages held at once (0: no cap). Must fit the largest page; the
  /// next page is prefetched only while current + next fit. Beside it, the pager's step cursor
  /// holds 13 bytes per vertex (22 on a predictive page) while it plays a page with bit blocks,
  /// and its background thread keeps the bytes of the largest page it has read, to read the next
  /// into.
  std::uint64_t memory_cap_bytes = 0;
  /// Load the next page on a background thread when playback enters a page (Bernardon et
  /// al., sec. 5.3: current and next codebooks resident, so playback does not wait).
  bool prefetch = true;
};

struct PagerStats {
  std::uint64_t reads = 0;          ///< read_step calls
  std::uint64_t stalls = 0;         ///< reads that waited for a page to come from disk
  double stall_seconds = 0;         ///< time spent in those waits
  double prepare_seconds = 0;       ///< time prepare() waited (set-up before playback, not a stall)
  std::uint64_t loads = 0;          ///< pages loaded (either thread)
  std::uint64_t prefetched = 0;     ///< pages loaded ahead by the background thread
  std::uint64_t recycled = 0;       ///< loads parsed into the memory of a page playback had left
  std::uint64_t resident_bytes = 0, peak_resident_bytes = 0;
};

/// Plays a compressed field back step by step, keeping the current and the next page
/// resident. Random access works (a page not resident is loaded, counted as a stall).
/// Output is bit-identical to CompressedField::read_step. One reader at a time.
class Pager {
public:
  explicit Pager(std::shared_ptr<const CompressedField> field, PagerOptions options = {});
  ~Pager();
  Pager(const Pager&) = delete;
  Pager& operator=(const Pager&) = delete;

  /// Starts loading the page of `step` in the background, for playback that will begin there
  /// (the constructor does this for step 0). Returns at once; a bad page is reported by the
  /// read that needs it.
  void start_at(std::uint64_t step);
  /// Returns once the page of `step` is resident (loading it here if no load is under way), so
  /// that playback from `step` does not wait. Its time is set-up (PagerStats::prepare_seconds),
  /// not a stall. Throws penumbra::Error naming the page if it is bad.
  void prepare(std::uint64_t step);
  /// Whether the page of `step` is loaded (a read of it would not wait).
  bool resident(std::uint64_t step) const;
  /// Decodes global step `step` for all vertices into out[vertex_count]: the field's values as
  /// float32 (narrow_through_map), or in double, keeping what each page's map holds.
  void read_step(std::uint64_t step, float* out);
  void read_step(std::uint64_t step, double* out);
  PagerStats stats() const;
  const CompressedField& field() const { return *m_field; }

private:
  /// read_step's stored values into out; returns the page's map.
  ValueMap decode_stored(std::uint64_t step, float* out);
  void prefetch_loop();
  void request_prefetch_locked(std::size_t page);
  /// Playback is on `page`: keeps it and the next, drops the rest, prefetches the next.
  void enter_page_locked(std::size_t page);
  /// Makes `page` resident, waiting for an in-flight load or loading it here (then current too).
  std::map<std::size_t, std::shared_ptr<const EncodedPage>>::iterator make_resident_locked(
      std::unique_lock<std::mutex>& lock, std::size_t page);
  void evict_locked(std::size_t keep_a, std::size_t keep_b);
  /// Gives the spare page to a load's buffers; returns it (null if none), to tell whether the
  /// load reused it.
  const EncodedPage* hand_spare_locked(PageBuffers& buffers);
  void insert_locked(std::size_t page, std::shared_ptr<const EncodedPage> data);

  std::shared_ptr<const CompressedField> m_field;
  PagerOptions m_options;
  mutable std::mutex m_mutex;
  std::condition_variable m_wake, m_loaded;
  std::map<std::size_t, std::shared_ptr<const EncodedPage>> m_resident;
  /// A page playback left that nothing else holds: the next load parses into its arrays
  /// instead of touching fresh memory.
  std::shared_ptr<const EncodedPage> m_spare;
  PageBuffers m_prefetch_buffers;  ///< the background thread's
  static constexpr std::size_t kNone = ~std::size_t(0);
  std::size_t m_request = kNone, m_loading = kNone, m_current = kNone;
  std::size_t m_start = 0;  ///< page of the last start_at(), kept while no page is current
  bool m_stop = false;
  PagerStats m_stats;
  StepCursor m_cursor;  ///< O(1) sequential steps of predictive pages
  std::vector<float> m_stored;  ///< the double read's stored values
  std::thread m_thread;
};

}  // namespace penumbra::compression

PNB_PUBLIC_END

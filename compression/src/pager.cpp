// SPDX-License-Identifier: BSD-3-Clause
// compression/src/pager.cpp -- current + next page resident, next page prefetched in background.
#include "penumbra/compression/pager.h"

#include <chrono>
#include <optional>
#include <string>
#include <thread>

#include "page_format.h"
#include "penumbra/compression/window_codec.h"
#include "penumbra/core/error.h"
#include "penumbra/core/thread_pool.h"

namespace penumbra::compression {

namespace {

// Memory a page takes once loaded, from its index entry: its payload's bytes once its coding is
// undone (up to 7 times those on disk), plus the per-vertex section offsets derived at load time
// for pages with bit blocks (4 bytes per vertex).
std::uint64_t loaded_bytes(const CompressedField& field, const PageEntry& page) {
  return detail::PageHeader::kBytes + page.payload_bytes + (page.method == PageMethod::vq ? 0 : field.info().vertex_count * 4);
}

}  // namespace

Pager::Pager(std::shared_ptr<const CompressedField> field, PagerOptions options)
    : m_field(std::move(field)), m_options(options) {
  require(m_field != nullptr, "Pager: null field");
  if (m_options.memory_cap_bytes)
    for (std::size_t i = 0; i < m_field->page_count(); ++i)
      if (loaded_bytes(*m_field, m_field->page(i)) > m_options.memory_cap_bytes)
        throw Error(ErrorCode::out_of_memory, "Pager: memory cap of " + std::to_string(m_options.memory_cap_bytes) +
                                                  " bytes is below the " +
                                                  std::to_string(loaded_bytes(*m_field, m_field->page(i))) +
                                                  " bytes of loaded page " + std::to_string(i));
  if (m_options.prefetch) {
    m_thread = std::thread([this] { prefetch_loop(); });
    // Playback usually starts at step 0: have its page on the way before the first read.
    if (m_field->page_count() > 0) start_at(0);
  }
}

Pager::~Pager() {
  {
    std::lock_guard<std::mutex> lock(m_mutex);
    m_stop = true;
  }
  m_wake.notify_all();
  if (m_thread.joinable()) m_thread.join();
}

PagerStats Pager::stats() const {
  std::lock_guard<std::mutex> lock(m_mutex);
  return m_stats;
}

void Pager::insert_locked(std::size_t page, std::shared_ptr<const EncodedPage> data) {
  if (m_resident.count(page)) return;
  m_stats.resident_bytes += data->resident_bytes();
  m_stats.peak_resident_bytes = std::max(m_stats.peak_resident_bytes, m_stats.resident_bytes);
  m_resident.emplace(page, std::move(data));
}

void Pager::evict_locked(std::size_t keep_a, std::size_t keep_b) {
  for (auto it = m_resident.begin(); it != m_resident.end();) {
    if (it->first == keep_a || it->first == keep_b) {
      ++it;
    } else {
      m_stats.resident_bytes -= it->second->resident_bytes();
      if (it->second.use_count() == 1) m_spare = std::move(it->second);
      it = m_resident.erase(it);
    }
  }
}

const EncodedPage* Pager::hand_spare_locked(PageBuffers& buffers) {
  // The spare was made by load_page, not const, and only this pager holds it.
  buffers.spare = std::const_pointer_cast<EncodedPage>(std::move(m_spare));
  return buffers.spare.get();
}

void Pager::request_prefetch_locked(std::size_t page) {
  if (m_loading == page || m_request == page) return;  // a load is on its way: it takes the spare
  bool wanted = m_options.prefetch && page < m_field->page_count() && !m_resident.count(page);
  if (wanted && m_options.memory_cap_bytes) {
    // The index entry stands in for the loaded size (they differ by a few vector headers).
    std::uint64_t held = 0;
    for (const auto& [index, data] : m_resident)
      if (index == m_current) held += data->resident_bytes();
    wanted = held + loaded_bytes(*m_field, m_field->page(page)) + 4096 <= m_options.memory_cap_bytes;
  }
  if (!wanted) {
    // No load will take the spare soon; under a cap its memory must not stay beside the pages.
    if (m_options.memory_cap_bytes) m_spare.reset();
    return;
  }
  m_request = page;
  m_wake.notify_all();
}

void Pager::prefetch_loop() {
  std::unique_lock<std::mutex> lock(m_mutex);
  while (true) {
    m_wake.wait(lock, [&] { return m_stop || m_request != kNone; });
    if (m_stop) return;
    const std::size_t page = m_request;
    m_request = kNone;
    if (m_resident.count(page)) continue;
    m_loading = page;
    const EncodedPage* spare = hand_spare_locked(m_prefetch_buffers);
    lock.unlock();
    std::shared_ptr<const EncodedPage> data;
    try {
      data = m_field->load_page(page, m_prefetch_buffers);
    } catch (const Error&) {
      // A bad page is reported by the read that needs it (loaded again there).
    }
    lock.lock();
    m_loading = kNone;
    if (data) {
      ++m_stats.loads;
      ++m_stats.prefetched;
      m_stats.recycled += spare != nullptr && data.get() == spare;
      // Keep it only if playback still wants it (current or the one after).
      if (page == m_current || page == m_current + 1 || (m_current == kNone && page == m_start))
        insert_locked(page, std::move(data));
    }
    m_loaded.notify_all();
  }
}

std::map<std::size_t, std::shared_ptr<const EncodedPage>>::iterator Pager::make_resident_locked(
    std::unique_lock<std::mutex>& lock, std::size_t page) {
  auto it = m_resident.find(page);
  if (it != m_resident.end()) return it;
  if (m_loading == page) {
    m_loaded.wait(lock, [&] { return m_loading != page; });
    it = m_resident.find(page);
    if (it != m_resident.end()) return it;
  }
  if (m_request == page) m_request = kNone;  // loaded here: the prefetcher must not load it again
  PageBuffers buffers;
  const EncodedPage* spare = hand_spare_locked(buffers);
  lock.unlock();
  auto loaded = m_field->load_page(page, buffers);  // throws naming the page if it is bad
  lock.lock();
  ++m_stats.loads;
  m_stats.recycled += spare != nullptr && loaded.get() == spare;
  m_current = page;
  evict_locked(page, page + 1);
  insert_locked(page, std::move(loaded));
  return m_resident.find(page);
}

void Pager::enter_page_locked(std::size_t page) {
  if (m_current != page) {
    m_current = page;
    evict_locked(page, page + 1);
  }
  request_prefetch_locked(page + 1);
}

bool Pager::resident(std::uint64_t step) const {
  const std::size_t page = m_field->page_of_step(step);
  std::lock_guard<std::mutex> lock(m_mutex);
  return m_resident.count(page) > 0;
}

void Pager::start_at(std::uint64_t step) {
  const std::size_t page = m_field->page_of_step(step);
  std::lock_guard<std::mutex> lock(m_mutex);
  if (m_current != page && !m_resident.count(page)) {
    // Playback moves there: what it held is no longer wanted.
    m_current = kNone;
    evict_locked(page, page + 1);
  }
  m_start = page;
  request_prefetch_locked(page);
}

void Pager::prepare(std::uint64_t step) {
  const std::size_t page = m_field->page_of_step(step);
  const auto start = std::chrono::steady_clock::now();
  std::unique_lock<std::mutex> lock(m_mutex);
  if (page != m_current) m_cursor.release();  // so that the page it leaves can be reused
  make_resident_locked(lock, page);
  enter_page_locked(page);
  m_stats.prepare_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

void Pager::read_step(std::uint64_t step, float* out) {
  require(out != nullptr, "Pager::read_step: null output");
  narrow_through_map(decode_stored(step, out), out, m_field->info().vertex_count);
}

void Pager::read_step(std::uint64_t step, double* out) {
  require(out != nullptr, "Pager::read_step: null output");
  m_stored.resize(m_field->info().vertex_count);
  apply_map(decode_stored(step, m_stored.data()), m_stored.data(), m_stored.size(), out);
}

ValueMap Pager::decode_stored(std::uint64_t step, float* out) {
  const std::size_t page = m_field->page_of_step(step);
  std::shared_ptr<const EncodedPage> data;
  bool load_waiting = false, load_running = false;
  {
    std::unique_lock<std::mutex> lock(m_mutex);
    ++m_stats.reads;
    auto it = m_resident.find(page);
    if (it == m_resident.end()) {
      ++m_stats.stalls;
      const auto start = std::chrono::steady_clock::now();
      it = make_resident_locked(lock, page);
      m_stats.stall_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    }
    data = it->second;
    // Playback leaves a page: the cursor lets go of it, so that its memory serves the next load.
    if (page != m_current) m_cursor.release();
    enter_page_locked(page);
    load_waiting = m_request != kNone;
    load_running = m_loading != kNone;
  }
  // While the next page's load waits for its thread to run, give up the core once per step: on a
  // busy machine playback that decodes as fast as it can would otherwise keep the loader from
  // starting before playback reaches its page (docs/pager.md, "Sharing two cores with the load").
  if (load_waiting) std::this_thread::yield();
  // And while it runs, decode on this thread alone, leaving the other cores to it: a load undoes
  // a zstd frame, and competing with a decode on every core it takes several times its time alone.
  std::optional<SerialScope> serial;
  if (load_running) serial.emplace();
  m_cursor.decode(data, std::uint32_t(step - data->first_step), out);
  return data->map;
}

}  // namespace penumbra::compression

// SPDX-License-Identifier: BSD-3-Clause
// viewer/src/render_queue.h -- render requests queued, bounded and superseded, for one StoreView
#pragma once
#include <condition_variable>
#include <cstddef>
#include <deque>
#include <future>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "store_view.h"

namespace penumbra::viewer {

/// How a queued request ended.
struct RenderResult {
  /// busy: the queue is full or stopping; bad_request: the request names no stored view.
  enum class Outcome { rendered, superseded, busy, bad_request, failed } outcome = Outcome::failed;
  RenderedView view;    ///< when rendered
  std::string message;  ///< why not, otherwise
};

/// One thread renders the requests in arrival order. A client's request still waiting when the
/// same client asks again is superseded (a page dragging the camera wants its latest view, not
/// every one on the way); at most `capacity` requests wait, and one more is refused, so that a
/// burst cannot grow memory or latency without bound.
class RenderQueue {
public:
  RenderQueue(std::unique_ptr<StoreView> view, std::size_t capacity);
  ~RenderQueue();
  RenderQueue(const RenderQueue&) = delete;
  RenderQueue& operator=(const RenderQueue&) = delete;

  std::future<RenderResult> submit(const std::string& client, const ViewRequest& request);
  const StoreInfo& info() const { return m_view->info(); }

private:
  struct Job {
    std::string client;
    ViewRequest request;
    std::promise<RenderResult> promise;
  };
  void run();
  RenderResult render(const ViewRequest& request);

  std::unique_ptr<StoreView> m_view;
  std::size_t m_capacity;
  std::mutex m_mutex;
  std::condition_variable m_wake;
  std::deque<Job> m_jobs;
  bool m_stopping = false;
  std::thread m_worker;
};

}  // namespace penumbra::viewer

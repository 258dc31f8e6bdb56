// SPDX-License-Identifier: BSD-3-Clause
// viewer/src/render_queue.cpp
#include "render_queue.h"

#include <exception>

#include "penumbra/core/error.h"

namespace penumbra::viewer {

RenderQueue::RenderQueue(std::unique_ptr<StoreView> view, std::size_t capacity)
    : m_view(std::move(view)), m_capacity(capacity), m_worker([this] { run(); }) {}

RenderQueue::~RenderQueue() {
  {
    std::lock_guard<std::mutex> lock(m_mutex);
    m_stopping = true;
  }
  m_wake.notify_all();
  m_worker.join();
  for (Job& job : m_jobs) job.promise.set_value({RenderResult::Outcome::busy, {}, "the viewer is stopping"});
}

std::future<RenderResult> RenderQueue::submit(const std::string& client, const ViewRequest& request) {
  std::promise<RenderResult> promise;
  std::future<RenderResult> result = promise.get_future();
  std::lock_guard<std::mutex> lock(m_mutex);
  for (auto it = m_jobs.begin(); it != m_jobs.end();)
    if (!client.empty() && it->client == client) {
      it->promise.set_value({RenderResult::Outcome::superseded, {}, "superseded by a newer request of the same page"});
      it = m_jobs.erase(it);
    } else {
      ++it;
    }
  if (m_stopping || m_jobs.size() >= m_capacity) {
    promise.set_value({RenderResult::Outcome::busy, {},
                       m_stopping ? "the viewer is stopping"
                                  : std::to_string(m_jobs.size()) + " renders are waiting already: try again"});
    return result;
  }
  m_jobs.push_back({client, request, std::move(promise)});
  m_wake.notify_one();
  return result;
}

void RenderQueue::run() {
  for (;;) {
    Job job;
    {
      std::unique_lock<std::mutex> lock(m_mutex);
      m_wake.wait(lock, [this] { return m_stopping || !m_jobs.empty(); });
      if (m_stopping) return;
      job = std::move(m_jobs.front());
      m_jobs.pop_front();
    }
    job.promise.set_value(render(job.request));
  }
}

RenderResult RenderQueue::render(const ViewRequest& request) {
  try {
    return {RenderResult::Outcome::rendered, m_view->render(request), {}};
  } catch (const Error& e) {
    return {e.code() == ErrorCode::invalid_argument ? RenderResult::Outcome::bad_request : RenderResult::Outcome::failed, {},
            e.what()};
  } catch (const std::exception& e) {
    return {RenderResult::Outcome::failed, {}, e.what()};
  }
}

}  // namespace penumbra::viewer

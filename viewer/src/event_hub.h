// SPDX-License-Identifier: BSD-3-Clause
// viewer/src/event_hub.h -- the events every open page receives (server-sent events): a bounded
// number of pages, each with a bounded queue, so a page that stops reading costs little
#pragma once
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "spacemouse_mapping.h"

namespace penumbra::viewer {

/// {"type":"motion","d_phi":...,"d_theta":...,"zoom":...,"d_time":...,"reset_view":...,"toggle_play":...}
std::string motion_json(const ViewEvent& event);
/// {"type":"status","message":"..."}
std::string status_json(const std::string& message);

class EventHub {
public:
  static constexpr std::size_t kMaxSubscribers = 8;
  static constexpr std::size_t kMaxQueued = 64;

  struct Subscriber;

  /// A new listener, which first receives the last status line; null when kMaxSubscribers
  /// already listen, or after close().
  std::shared_ptr<Subscriber> subscribe();
  void unsubscribe(const std::shared_ptr<Subscriber>& subscriber);
  std::size_t subscribers() const;

  /// To every listener. Motion waiting in a listener's queue is merged with it (changes added,
  /// zooms multiplied), so a page that reads late still gets the whole motion; events with a
  /// button's action stay apart. A full queue drops its oldest event.
  void publish(const ViewEvent& event);
  /// To every listener, and first to each later one.
  void publish_status(const std::string& message);

  /// The listener's waiting events as server-sent event text ("data: JSON\n\n" each), waiting at
  /// most `timeout` for one: empty when none came, nothing once the hub is closed.
  std::optional<std::string> next(Subscriber& subscriber, std::chrono::milliseconds timeout);
  /// Wakes every waiting next() and refuses new listeners: the server is stopping.
  void close();

private:
  template <typename Entry>
  void enqueue(const Entry& entry);

  mutable std::mutex m_mutex;
  std::condition_variable m_changed;
  std::vector<std::shared_ptr<Subscriber>> m_subscribers;
  std::string m_last_status;
  bool m_closed = false;
};

}  // namespace penumbra::viewer

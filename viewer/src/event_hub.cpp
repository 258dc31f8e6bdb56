// SPDX-License-Identifier: BSD-3-Clause
// viewer/src/event_hub.cpp -- events as JSON, queued per page, motion merged while it waits
#include "event_hub.h"

#include <algorithm>
#include <cstdio>
#include <variant>

namespace penumbra::viewer {
namespace {

// Six significant digits, in a form JSON accepts; adding 0.0 turns -0 into 0.
std::string number(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.6g", value + 0.0);
  return text;
}

std::string quoted(const std::string& text) {
  std::string out = "\"";
  for (const char c : text) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      char escape[8];
      std::snprintf(escape, sizeof escape, "\\u%04x", static_cast<unsigned>(c));
      out += escape;
    } else {
      out += c;
    }
  }
  return out + "\"";
}

bool has_action(const ViewEvent& e) { return e.reset_view || e.toggle_play; }

ViewEvent merged(ViewEvent a, const ViewEvent& b) {
  a.d_phi += b.d_phi;
  a.d_theta += b.d_theta;
  a.d_time += b.d_time;
  a.zoom *= b.zoom;
  return a;
}

struct Status {
  std::string json;
};

}  // namespace

struct EventHub::Subscriber {
  std::deque<std::variant<ViewEvent, Status>> queue;

  void add(const ViewEvent& event) {
    if (!queue.empty() && !has_action(event))
      if (auto* last = std::get_if<ViewEvent>(&queue.back()); last && !has_action(*last)) {
        *last = merged(*last, event);
        return;
      }
    push(event);
  }
  void add(const Status& status) { push(status); }
  void push(std::variant<ViewEvent, Status> entry) {
    if (queue.size() == kMaxQueued) queue.pop_front();
    queue.push_back(std::move(entry));
  }
  std::string drain() {
    std::string text;
    for (const auto& entry : queue)
      text += "data: " + (std::holds_alternative<ViewEvent>(entry) ? motion_json(std::get<ViewEvent>(entry)) : std::get<Status>(entry).json) + "\n\n";
    queue.clear();
    return text;
  }
};

std::string motion_json(const ViewEvent& e) {
  return "{\"type\":\"motion\",\"d_phi\":" + number(e.d_phi) + ",\"d_theta\":" + number(e.d_theta) +
         ",\"zoom\":" + number(e.zoom) + ",\"d_time\":" + number(e.d_time) +
         ",\"reset_view\":" + (e.reset_view ? "true" : "false") + ",\"toggle_play\":" + (e.toggle_play ? "true" : "false") + "}";
}

std::string status_json(const std::string& message) {
  return "{\"type\":\"status\",\"message\":" + quoted(message) + "}";
}

std::shared_ptr<EventHub::Subscriber> EventHub::subscribe() {
  std::lock_guard<std::mutex> lock(m_mutex);
  if (m_closed || m_subscribers.size() >= kMaxSubscribers) return nullptr;
  auto subscriber = std::make_shared<Subscriber>();
  if (!m_last_status.empty()) subscriber->add(Status{m_last_status});
  m_subscribers.push_back(subscriber);
  return subscriber;
}

void EventHub::unsubscribe(const std::shared_ptr<Subscriber>& subscriber) {
  std::lock_guard<std::mutex> lock(m_mutex);
  m_subscribers.erase(std::remove(m_subscribers.begin(), m_subscribers.end(), subscriber), m_subscribers.end());
}

std::size_t EventHub::subscribers() const {
  std::lock_guard<std::mutex> lock(m_mutex);
  return m_subscribers.size();
}

template <typename Entry>
void EventHub::enqueue(const Entry& entry) {
  for (const auto& subscriber : m_subscribers) subscriber->add(entry);
  m_changed.notify_all();
}

void EventHub::publish(const ViewEvent& event) {
  std::lock_guard<std::mutex> lock(m_mutex);
  enqueue(event);
}

void EventHub::publish_status(const std::string& message) {
  std::lock_guard<std::mutex> lock(m_mutex);
  m_last_status = status_json(message);
  enqueue(Status{m_last_status});
}

std::optional<std::string> EventHub::next(Subscriber& subscriber, std::chrono::milliseconds timeout) {
  std::unique_lock<std::mutex> lock(m_mutex);
  m_changed.wait_for(lock, timeout, [&] { return m_closed || !subscriber.queue.empty(); });
  if (m_closed) return std::nullopt;
  return subscriber.drain();
}

void EventHub::close() {
  {
    std::lock_guard<std::mutex> lock(m_mutex);
    m_closed = true;
  }
  m_changed.notify_all();
}

}  // namespace penumbra::viewer

// SPDX-License-Identifier: BSD-3-Clause
// tests/viewer/event_hub_test.cpp -- the pages' events: JSON, the last status for a new page,
// motion merged while it waits, bounded pages and queues
#include <gtest/gtest.h>

#include <cmath>

#include "event_hub.h"

namespace penumbra::viewer {
namespace {

using std::chrono::milliseconds;

std::size_t count(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (auto at = text.find(what); at != std::string::npos; at = text.find(what, at + what.size())) ++n;
  return n;
}

TEST(ViewServerEvents, Json) {
  ViewEvent e;
  e.d_phi = -1.5;
  e.d_time = 0.25;
  e.zoom = 1.0 / 1024;
  e.toggle_play = true;
  EXPECT_EQ(motion_json(e), "{\"type\":\"motion\",\"d_phi\":-1.5,\"d_theta\":0,\"zoom\":0.000976562,\"d_time\":0.25,"
                            "\"reset_view\":false,\"toggle_play\":true}");
  e = ViewEvent{};
  e.d_phi = -0.0;
  EXPECT_NE(motion_json(e).find("\"d_phi\":0,"), std::string::npos);
  EXPECT_EQ(status_json("3D mouse: \"x\"\\\n\x01 é"), "{\"type\":\"status\",\"message\":\"3D mouse: \\\"x\\\"\\\\\\u000a\\u0001 é\"}");
}

TEST(ViewServerEvents, ANewPageGetsTheLastStatusFirst) {
  EventHub hub;
  hub.publish_status("no 3D mouse found");
  hub.publish_status("3D mouse connected: test");
  auto page = hub.subscribe();
  ASSERT_TRUE(page);
  EXPECT_EQ(hub.next(*page, milliseconds(0)), "data: " + status_json("3D mouse connected: test") + "\n\n");
  EXPECT_EQ(hub.next(*page, milliseconds(10)), "");
}

TEST(ViewServerEvents, MotionWaitingIsMergedButButtonsStayApart) {
  EventHub hub;
  auto page = hub.subscribe();
  ViewEvent turn;
  turn.d_phi = 1;
  turn.d_time = -0.5;
  turn.zoom = 2;
  for (int i = 0; i < 100; ++i) hub.publish(turn);
  ViewEvent reset;
  reset.reset_view = true;
  hub.publish(reset);
  hub.publish(turn);
  ViewEvent sum;
  sum.d_phi = 100;
  sum.d_time = -50;
  sum.zoom = std::pow(2.0, 100);
  EXPECT_EQ(hub.next(*page, milliseconds(0)),
            "data: " + motion_json(sum) + "\n\ndata: " + motion_json(reset) + "\n\ndata: " + motion_json(turn) + "\n\n");
}

TEST(ViewServerEvents, AStalledPageHoldsABoundedQueue) {
  EventHub hub;
  auto stalled = hub.subscribe();
  ViewEvent play;
  play.toggle_play = true;
  for (int i = 0; i < 10000; ++i) {
    hub.publish_status("status " + std::to_string(i));
    hub.publish(play);
  }
  const std::string text = *hub.next(*stalled, milliseconds(0));
  EXPECT_EQ(count(text, "data: "), EventHub::kMaxQueued);
  EXPECT_NE(text.find("status 9999"), std::string::npos) << "the newest are kept";
}

TEST(ViewServerEvents, BoundedPagesAndClose) {
  EventHub hub;
  std::vector<std::shared_ptr<EventHub::Subscriber>> pages;
  for (std::size_t i = 0; i < EventHub::kMaxSubscribers; ++i) pages.push_back(hub.subscribe());
  for (const auto& p : pages) EXPECT_TRUE(p);
  EXPECT_FALSE(hub.subscribe());
  hub.unsubscribe(pages.back());
  pages.back() = hub.subscribe();
  EXPECT_TRUE(pages.back());
  EXPECT_EQ(hub.subscribers(), EventHub::kMaxSubscribers);
  hub.close();
  EXPECT_EQ(hub.next(*pages[0], milliseconds(1000)), std::nullopt);
  hub.unsubscribe(pages[0]);
  EXPECT_FALSE(hub.subscribe());
}

}  // namespace
}  // namespace penumbra::viewer

// SPDX-License-Identifier: BSD-3-Clause
// tests/viewer/spacemouse_device_test.cpp -- the 3D mouse's reader on a scripted device: reports
// become events, the device unplugs and comes back, a refused device and failures are status lines
#include <gtest/gtest.h>

#include <condition_variable>
#include <functional>
#include <mutex>
#include <numeric>
#include <sstream>
#include <stdexcept>

#include "penumbra/core/error.h"
#include "scripted_transport.h"
#include "spacemouse_device.h"

namespace penumbra::viewer {
namespace {

using std::chrono::milliseconds;

// What the reader delivered, waited for from the test's thread.
struct Recorder {
  std::mutex mutex;
  std::condition_variable changed;
  std::vector<ViewEvent> events;
  std::vector<std::string> statuses;

  SpaceMouse::MotionHandler on_motion() {
    return [this](const ViewEvent& e) {
      std::lock_guard<std::mutex> lock(mutex);
      events.push_back(e);
      changed.notify_all();
    };
  }
  SpaceMouse::StatusHandler on_status() {
    return [this](const std::string& s) {
      std::lock_guard<std::mutex> lock(mutex);
      statuses.push_back(s);
      changed.notify_all();
    };
  }
  bool wait_until(const std::function<bool()>& done) {
    std::unique_lock<std::mutex> lock(mutex);
    return changed.wait_for(lock, std::chrono::seconds(10), done);
  }
  std::size_t count(const std::string& status) const { return std::count(statuses.begin(), statuses.end(), status); }
};

constexpr SpaceMouseOptions kQuick{MappingSettings{1.0, 15}, milliseconds(20), milliseconds(20)};

// The older layout, as a device sends it while the cap slides right and twists counterclockwise
// (seen from above), then the cap back at rest, then button 1 pressed and released.
std::vector<ScriptedReport> slide_twist_and_click() {
  std::vector<ScriptedReport> r;
  for (int i = 0; i < 5; ++i) {
    r.push_back({milliseconds(10), {0x01, 0x5e, 0x01, 0x00, 0x00, 0x00, 0x00}});  // x +350
    r.push_back({milliseconds(0), {0x02, 0x00, 0x00, 0x00, 0x00, 0xa2, 0xfe}});   // rz -350
  }
  r.push_back({milliseconds(10), {0x01, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00}});
  r.push_back({milliseconds(0), {0x02, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00}});
  r.push_back({milliseconds(10), {0x03, 0x01, 0x00}});
  r.push_back({milliseconds(10), {0x03, 0x00, 0x00}});
  return r;
}

double sum(const std::vector<ViewEvent>& events, double ViewEvent::*field) {
  return std::accumulate(events.begin(), events.end(), 0.0, [&](double s, const ViewEvent& e) { return s + e.*field; });
}

TEST(SpaceMouseDevice, ReportsBecomeEventsUntilUnpluggedThenItComesBack) {
  auto transport = std::make_unique<ScriptedTransport>(slide_twist_and_click());
  ScriptedTransport& device = *transport;
  Recorder seen;
  SpaceMouse mouse(std::move(transport), kQuick, seen.on_motion(), seen.on_status());
  mouse.start();
  ASSERT_TRUE(seen.wait_until([&] { return seen.count(kNoDeviceMessage) == 1; }));

  device.plug_in();
  ASSERT_TRUE(seen.wait_until([&] { return seen.count(kUnpluggedMessage) == 1; }));
  {
    std::lock_guard<std::mutex> lock(seen.mutex);
    EXPECT_EQ(seen.statuses, (std::vector<std::string>{kNoDeviceMessage, "3D mouse connected: scripted 3D mouse", kUnpluggedMessage}));
    // Eleven reports with the cap displaced (the translation's return to rest comes before the
    // rotation's), one press; the rest and the release are idle.
    ASSERT_EQ(seen.events.size(), 12u);
    const std::vector<ViewEvent> motion(seen.events.begin(), seen.events.end() - 1);
    // Each report stands for the time since the one before, at least its delay and at most
    // kMaxReportSeconds: five translation reports 10 ms apart, and the twist held over four of
    // them and the return to rest.
    EXPECT_GE(sum(motion, &ViewEvent::d_time), 5 * 0.010 * kTimeStepsPerSecond);
    EXPECT_LE(sum(motion, &ViewEvent::d_time), 5 * kMaxReportSeconds * kTimeStepsPerSecond);
    EXPECT_GE(sum(motion, &ViewEvent::d_phi), 5 * 0.010 * kOrbitDegreesPerSecond);
    EXPECT_LE(sum(motion, &ViewEvent::d_phi), 10 * kMaxReportSeconds * kOrbitDegreesPerSecond);
    for (const ViewEvent& e : motion) EXPECT_FALSE(e.reset_view || e.toggle_play || e.d_theta != 0 || e.zoom != 1);
    EXPECT_TRUE(seen.events.back().reset_view);
  }

  device.plug_in();
  ASSERT_TRUE(seen.wait_until([&] { return seen.count(kUnpluggedMessage) == 2; }));
  mouse.stop();
  std::lock_guard<std::mutex> lock(seen.mutex);
  EXPECT_EQ(seen.events.size(), 24u);
  EXPECT_EQ(seen.count("3D mouse connected: scripted 3D mouse"), 2u);
  EXPECT_EQ(seen.count(kNoDeviceMessage), 1u) << "after an unplug, 'unplugged' stays until one comes back";
  EXPECT_EQ(device.times_opened(), 2);
}

TEST(SpaceMouseDevice, NewerLayoutReports) {
  // Combined reports: z +350 (pushed down) and rx +350 (tilted towards the user).
  const std::vector<ScriptedReport> reports(3, ScriptedReport{milliseconds(10), {0x01, 0, 0, 0, 0, 0x5e, 0x01, 0x5e, 0x01, 0, 0, 0, 0}});
  auto transport = std::make_unique<ScriptedTransport>(reports);
  transport->plug_in();
  Recorder seen;
  SpaceMouse mouse(std::move(transport), kQuick, seen.on_motion(), seen.on_status());
  mouse.start();
  ASSERT_TRUE(seen.wait_until([&] { return seen.count(kUnpluggedMessage) == 1; }));
  mouse.stop();
  ASSERT_EQ(seen.events.size(), 3u);
  for (const ViewEvent& e : seen.events) {
    EXPECT_GT(e.zoom, 1);
    EXPECT_GT(e.d_theta, 0);
    EXPECT_EQ(e.d_phi, 0);
  }
}

TEST(SpaceMouseDevice, PermissionDeniedSaysWhatToDo) {
  auto transport = std::make_unique<ScriptedTransport>(slide_twist_and_click());
  ScriptedTransport& device = *transport;
  device.deny_access(true);
  device.plug_in();
  Recorder seen;
  SpaceMouse mouse(std::move(transport), kQuick, seen.on_motion(), seen.on_status());
  mouse.start();
  ASSERT_TRUE(seen.wait_until([&] { return !seen.statuses.empty(); }));
  EXPECT_NE(mouse.status().find("permission denied"), std::string::npos);
  EXPECT_NE(mouse.status().find("udev rule"), std::string::npos);
  // Once the rule is in place the device is replugged.
  device.deny_access(false);
  device.plug_in();
  ASSERT_TRUE(seen.wait_until([&] { return seen.count(kUnpluggedMessage) == 1; }));
  mouse.stop();
  EXPECT_EQ(seen.events.size(), 12u);
}

TEST(SpaceMouseDevice, AFailingCallbackEndsTheReaderNotTheProgram) {
  auto transport = std::make_unique<ScriptedTransport>(slide_twist_and_click());
  transport->plug_in();
  Recorder seen;
  SpaceMouse mouse(std::move(transport), kQuick, [](const ViewEvent&) { throw std::runtime_error("no room"); },
                   seen.on_status());
  mouse.start();
  ASSERT_TRUE(seen.wait_until([&] { return seen.count("3D mouse stopped: no room") == 1; }));
  mouse.stop();
  EXPECT_EQ(mouse.status(), "3D mouse stopped: no room");
}

TEST(SpaceMouseDevice, StopsWhileWaitingForADevice) {
  Recorder seen;
  SpaceMouse mouse(std::make_unique<ScriptedTransport>(std::vector<ScriptedReport>{}),
                   SpaceMouseOptions{MappingSettings{}, milliseconds(100), milliseconds(500)}, seen.on_motion(),
                   seen.on_status());
  mouse.start();
  ASSERT_TRUE(seen.wait_until([&] { return !seen.statuses.empty(); }));
  const auto t0 = std::chrono::steady_clock::now();
  mouse.stop();
  EXPECT_LT(std::chrono::steady_clock::now() - t0, std::chrono::seconds(2));
  EXPECT_EQ(mouse.status(), kNoDeviceMessage);
}

TEST(SpaceMouseDevice, ReportScript) {
  std::istringstream script(
      "# delay, then the report\n"
      "0 01 5e 01 f4 ff 00 00\n"
      "\n"
      "  16 03 1 0   # button 1\n");
  const auto reports = read_report_script(script, "s.txt");
  ASSERT_EQ(reports.size(), 2u);
  EXPECT_EQ(reports[0].delay, milliseconds(0));
  EXPECT_EQ(reports[0].bytes, (std::vector<std::uint8_t>{0x01, 0x5e, 0x01, 0xf4, 0xff, 0x00, 0x00}));
  EXPECT_EQ(reports[1].delay, milliseconds(16));
  EXPECT_EQ(reports[1].bytes, (std::vector<std::uint8_t>{0x03, 0x01, 0x00}));
  std::string too_long = "10";
  for (int i = 0; i < 65; ++i) too_long += " 00";
  for (const std::string& bad : std::vector<std::string>{"10\n", "x 01\n", "-1 01\n", "60001 01\n", "10 100\n", "10 0g\n", too_long}) {
    std::istringstream in(bad);
    try {
      read_report_script(in, "s.txt");
      ADD_FAILURE() << bad;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("s.txt line 1"), std::string::npos) << e.what();
    }
  }
  EXPECT_THROW(read_report_script_file("/nonexistent/script.txt"), Error);
}

}  // namespace
}  // namespace penumbra::viewer

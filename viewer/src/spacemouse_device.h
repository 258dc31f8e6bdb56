// SPDX-License-Identifier: BSD-3-Clause
// viewer/src/spacemouse_device.h -- the 3D mouse's reader: a thread that reads reports through a
// transport, parses and maps them, and hands view events and status lines to callbacks
#pragma once
#include <atomic>
#include <chrono>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "spacemouse_mapping.h"
#include "spacemouse_transport.h"

namespace penumbra::viewer {

struct SpaceMouseOptions {
  MappingSettings mapping;
  std::chrono::milliseconds read_timeout{100};   ///< how long a read waits; bounds stop()'s wait
  std::chrono::milliseconds arrival_wait{500};   ///< how long one wait for a hotplug arrival lasts
};

/// Reads the 3D mouse on its own thread from start() to stop() (or destruction): opens the
/// device, turns each report into a ViewEvent (an idle one is not delivered), and when the device
/// is missing, refused or unplugged says so and waits for one to arrive. Status lines:
/// "no 3D mouse found", the transport's "3D mouse connected: ..." or "3D mouse: permission
/// denied ...", "3D mouse unplugged; waiting for it to come back". The callbacks run on the
/// reader's thread; an exception from them, or from anything else there, ends the reader with a
/// status line and never reaches the host program.
class SpaceMouse {
public:
  using MotionHandler = std::function<void(const ViewEvent&)>;
  using StatusHandler = std::function<void(const std::string&)>;

  SpaceMouse(std::unique_ptr<SpaceMouseTransport> transport, SpaceMouseOptions options, MotionHandler on_motion,
             StatusHandler on_status);
  ~SpaceMouse();
  SpaceMouse(const SpaceMouse&) = delete;
  SpaceMouse& operator=(const SpaceMouse&) = delete;

  void start();
  /// Returns once the reader's thread has ended (within about one read timeout or arrival wait).
  void stop();
  /// The last status line; empty before the first.
  std::string status() const;

private:
  void run();
  void loop();
  TransportResult connect();
  TransportResult read_until_gone();
  void set_status(const std::string& message);

  std::unique_ptr<SpaceMouseTransport> m_transport;
  SpaceMouseOptions m_options;
  MotionHandler m_on_motion;
  StatusHandler m_on_status;
  std::atomic<bool> m_stopping{false};
  mutable std::mutex m_status_mutex;
  std::string m_status;
  std::thread m_thread;
};

inline constexpr const char* kNoDeviceMessage = "no 3D mouse found";
inline constexpr const char* kUnpluggedMessage = "3D mouse unplugged; waiting for it to come back";

}  // namespace penumbra::viewer

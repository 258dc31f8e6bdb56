// SPDX-License-Identifier: BSD-3-Clause
// viewer/src/spacemouse_transport.h -- how the 3D mouse's reader reaches a device: the system's
// USB (libusb_transport.h) or a script of recorded reports (scripted_transport.h)
#pragma once
#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace penumbra::viewer {

enum class TransportResult {
  ok,
  timeout,        ///< no report within the time given
  unplugged,      ///< the open device has left
  not_found,      ///< no supported device is attached
  access_denied,  ///< one is attached but this user may not open it
  failed,         ///< anything else; the message says what
};

/// A result and, for the person running the viewer, one line saying what it means.
struct TransportStatus {
  TransportResult result = TransportResult::ok;
  std::string message;
};

/// One supported device at a time, used from one thread (SpaceMouse's). No call throws.
class SpaceMouseTransport {
public:
  virtual ~SpaceMouseTransport() = default;
  /// Finds a supported device and claims its HID interface. ok: the message names the device.
  virtual TransportStatus open() = 0;
  /// Reads one interrupt report of the open device into `report` (resized to the report's
  /// length), waiting at most `timeout`: ok, timeout, unplugged or failed.
  virtual TransportStatus read(std::vector<std::uint8_t>& report, std::chrono::milliseconds timeout) = 0;
  /// Releases the open device; harmless when none is open.
  virtual void close() = 0;
  /// Waits at most `timeout` for a device to arrive: true when one did, or, where the system
  /// sends no hotplug notifications, when it is time to look again.
  virtual bool wait_for_arrival(std::chrono::milliseconds timeout) = 0;
};

/// The system's USB (libusb_transport.h), or null where penumbra-view is built without libusb-1.0.
std::unique_ptr<SpaceMouseTransport> system_spacemouse_transport();

}  // namespace penumbra::viewer

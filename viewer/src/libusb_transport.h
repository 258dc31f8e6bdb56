// SPDX-License-Identifier: BSD-3-Clause
// viewer/src/libusb_transport.h -- 3Dconnexion devices on the system's USB, through libusb-1.0
#pragma once
#include <cstdint>
#include <memory>

#include "spacemouse_transport.h"

namespace penumbra::viewer {

inline constexpr std::uint16_t k3DconnexionVendor = 0x256f;
/// Logitech, which made 3Dconnexion's older devices under its own vendor id.
inline constexpr std::uint16_t kLogitechVendor = 0x046d;

/// Whether a device is a 3Dconnexion one: any product of 3Dconnexion's vendor id, and of
/// Logitech's only the range 3Dconnexion used (0xc603 to 0xc640), which leaves out Logitech's
/// mice, keyboards and receivers.
bool is_3dconnexion(std::uint16_t vendor, std::uint16_t product);

/// Where a device is attached, for messages.
struct UsbLocation {
  int bus = 0;
  int address = 0;
  std::uint16_t vendor = 0;
  std::uint16_t product = 0;
};

/// What a libusb error from opening or claiming the device at `where` means for its user:
/// LIBUSB_ERROR_ACCESS is access_denied and points to the udev rule, LIBUSB_ERROR_NO_DEVICE
/// (it left meanwhile) is not_found, the others are failed and say which.
TransportStatus open_failure(int libusb_error, const UsbLocation& where);

/// The first attached 3Dconnexion device with a HID interface and an interrupt IN endpoint. The
/// kernel's driver is detached while the interface is claimed (and attached again on close()),
/// arrivals come from libusb's hotplug notifications, or, where the system has none, every
/// couple of seconds a new look. Where USB cannot be used at all (no /dev/bus/usb), open()
/// reports no device, as it does when none is attached.
class LibusbTransport : public SpaceMouseTransport {
public:
  LibusbTransport();
  ~LibusbTransport() override;
  LibusbTransport(const LibusbTransport&) = delete;
  LibusbTransport& operator=(const LibusbTransport&) = delete;

  TransportStatus open() override;
  TransportStatus read(std::vector<std::uint8_t>& report, std::chrono::milliseconds timeout) override;
  void close() override;
  bool wait_for_arrival(std::chrono::milliseconds timeout) override;

  struct State;  ///< libusb's handles, private to libusb_transport.cpp

private:
  std::unique_ptr<State> m_state;
};

}  // namespace penumbra::viewer

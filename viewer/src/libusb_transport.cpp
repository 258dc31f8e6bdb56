// SPDX-License-Identifier: BSD-3-Clause
// viewer/src/libusb_transport.cpp -- find, claim and read a 3Dconnexion device with libusb-1.0
#include "libusb_transport.h"

#include <libusb.h>
#include <sys/time.h>

#include <algorithm>
#include <cstdio>
#include <optional>
#include <thread>

#include "spacemouse_device.h"

namespace penumbra::viewer {
namespace {

using Clock = std::chrono::steady_clock;

/// Where the system sends no hotplug notifications, how often the devices are listed again.
constexpr std::chrono::seconds kPollPeriod{2};
constexpr std::uint16_t kFirstLogitech3Dconnexion = 0xc603;
constexpr std::uint16_t kLastLogitech3Dconnexion = 0xc640;

struct HidEndpoint {
  int interface_number = -1;
  unsigned char address = 0;
  int packet_size = 0;
};

std::string ids(const UsbLocation& where) {
  char text[64];
  std::snprintf(text, sizeof text, "bus %d device %d (%04x:%04x)", where.bus, where.address, where.vendor, where.product);
  return text;
}

std::string usb_error(int code) { return std::string(libusb_error_name(code)) + ": " + libusb_strerror(code); }

bool is_interrupt_in(const libusb_endpoint_descriptor& e) {
  return (e.bEndpointAddress & LIBUSB_ENDPOINT_DIR_MASK) == LIBUSB_ENDPOINT_IN &&
         (e.bmAttributes & LIBUSB_TRANSFER_TYPE_MASK) == LIBUSB_TRANSFER_TYPE_INTERRUPT;
}

std::optional<HidEndpoint> hid_endpoint_in(const libusb_config_descriptor& config) {
  for (int i = 0; i < config.bNumInterfaces; ++i) {
    if (config.interface[i].num_altsetting < 1) continue;
    const libusb_interface_descriptor& alt = config.interface[i].altsetting[0];
    if (alt.bInterfaceClass != LIBUSB_CLASS_HID) continue;
    for (int k = 0; k < alt.bNumEndpoints; ++k)
      if (is_interrupt_in(alt.endpoint[k]))
        return HidEndpoint{alt.bInterfaceNumber, alt.endpoint[k].bEndpointAddress, alt.endpoint[k].wMaxPacketSize};
  }
  return std::nullopt;
}

// The active configuration's, or, for a device not configured yet, the first one's.
std::optional<HidEndpoint> hid_endpoint_in(libusb_device* device) {
  libusb_config_descriptor* config = nullptr;
  if (libusb_get_active_config_descriptor(device, &config) != 0 && libusb_get_config_descriptor(device, 0, &config) != 0)
    return std::nullopt;
  const auto found = hid_endpoint_in(*config);
  libusb_free_config_descriptor(config);
  return found;
}

// The device's product string as printable ASCII, for a status line.
std::string product_name(libusb_device_handle* handle, std::uint8_t index) {
  unsigned char text[128] = {};
  const int n = index == 0 ? 0 : libusb_get_string_descriptor_ascii(handle, index, text, sizeof text);
  std::string name;
  for (int i = 0; i < n; ++i) name.push_back(text[i] >= 0x20 && text[i] < 0x7f ? static_cast<char>(text[i]) : '?');
  return name.empty() ? "3Dconnexion device" : name;
}

// The kernel's HID driver holds the interface; libusb detaches it while claimed and attaches it
// again on release, or, where it cannot do that by itself, it is detached here.
void detach_kernel_driver(libusb_device_handle* handle, int interface_number) {
  if (libusb_set_auto_detach_kernel_driver(handle, 1) == LIBUSB_SUCCESS) return;
  if (libusb_kernel_driver_active(handle, interface_number) == 1) libusb_detach_kernel_driver(handle, interface_number);
}

timeval as_timeval(Clock::duration d) {
  const auto us = std::chrono::duration_cast<std::chrono::microseconds>(d).count();
  return timeval{static_cast<time_t>(us / 1000000), static_cast<suseconds_t>(us % 1000000)};
}

}  // namespace

struct LibusbTransport::State {
  libusb_context* context = nullptr;
  int init_error = LIBUSB_SUCCESS;
  bool hotplug = false;
  std::vector<libusb_hotplug_callback_handle> callbacks;
  int arrived = 0;  ///< set by the hotplug callback, which runs inside libusb_handle_events_*
  bool departed = false;
  Clock::time_point next_poll{};
  libusb_device* device = nullptr;  ///< the open one
  libusb_device_handle* handle = nullptr;
  HidEndpoint endpoint;
};

namespace {

int LIBUSB_CALL on_hotplug(libusb_context*, libusb_device* device, libusb_hotplug_event event, void* user) {
  auto& state = *static_cast<LibusbTransport::State*>(user);
  libusb_device_descriptor d{};
  if (libusb_get_device_descriptor(device, &d) != 0 || !is_3dconnexion(d.idVendor, d.idProduct)) return 0;
  if (event == LIBUSB_HOTPLUG_EVENT_DEVICE_ARRIVED) state.arrived = 1;
  else if (device == state.device) state.departed = true;
  return 0;
}

void register_hotplug(LibusbTransport::State& state) {
  if (!libusb_has_capability(LIBUSB_CAP_HAS_HOTPLUG)) return;
  for (const int vendor : {int{k3DconnexionVendor}, int{kLogitechVendor}}) {
    libusb_hotplug_callback_handle callback = 0;
    if (libusb_hotplug_register_callback(state.context, LIBUSB_HOTPLUG_EVENT_DEVICE_ARRIVED | LIBUSB_HOTPLUG_EVENT_DEVICE_LEFT,
                                         LIBUSB_HOTPLUG_NO_FLAGS, vendor, LIBUSB_HOTPLUG_MATCH_ANY, LIBUSB_HOTPLUG_MATCH_ANY,
                                         on_hotplug, &state, &callback) == LIBUSB_SUCCESS)
      state.callbacks.push_back(callback);
  }
  state.hotplug = state.callbacks.size() == 2;
}

TransportStatus claim(LibusbTransport::State& state, libusb_device* device, const HidEndpoint& endpoint,
                      const libusb_device_descriptor& d) {
  const UsbLocation where{libusb_get_bus_number(device), libusb_get_device_address(device), d.idVendor, d.idProduct};
  libusb_device_handle* handle = nullptr;
  if (const int r = libusb_open(device, &handle); r != LIBUSB_SUCCESS) return open_failure(r, where);
  detach_kernel_driver(handle, endpoint.interface_number);
  if (const int r = libusb_claim_interface(handle, endpoint.interface_number); r != LIBUSB_SUCCESS) {
    libusb_close(handle);
    return open_failure(r, where);
  }
  state.handle = handle;
  state.device = device;
  state.endpoint = endpoint;
  state.departed = false;
  return {TransportResult::ok, "3D mouse connected: " + product_name(handle, d.iProduct) + " on " + ids(where)};
}

}  // namespace

bool is_3dconnexion(std::uint16_t vendor, std::uint16_t product) {
  if (vendor == k3DconnexionVendor) return true;
  return vendor == kLogitechVendor && product >= kFirstLogitech3Dconnexion && product <= kLastLogitech3Dconnexion;
}

TransportStatus open_failure(int libusb_error, const UsbLocation& where) {
  switch (libusb_error) {
    case LIBUSB_ERROR_ACCESS:
      return {TransportResult::access_denied,
              "3D mouse: permission denied on " + ids(where) + ": see viewer/README.md for the udev rule"};
    case LIBUSB_ERROR_NO_DEVICE:
      return {TransportResult::not_found, kNoDeviceMessage};
    case LIBUSB_ERROR_NOT_FOUND:
      return {TransportResult::failed, "3D mouse on " + ids(where) + ": its HID interface cannot be claimed (" + usb_error(libusb_error) + ")"};
    case LIBUSB_ERROR_BUSY:
      return {TransportResult::failed, "3D mouse on " + ids(where) + " is in use by another program (spacenavd?)"};
    default:
      return {TransportResult::failed, "3D mouse on " + ids(where) + " cannot be opened (" + usb_error(libusb_error) + ")"};
  }
}

LibusbTransport::LibusbTransport() : m_state(std::make_unique<State>()) {
  State& s = *m_state;
  s.init_error = libusb_init(&s.context);
  if (s.init_error != LIBUSB_SUCCESS) {
    s.context = nullptr;
    return;
  }
  register_hotplug(s);
}

LibusbTransport::~LibusbTransport() {
  close();
  if (!m_state->context) return;
  for (const auto callback : m_state->callbacks) libusb_hotplug_deregister_callback(m_state->context, callback);
  libusb_exit(m_state->context);
}

TransportStatus LibusbTransport::open() {
  State& s = *m_state;
  close();
  if (!s.context) return {TransportResult::not_found, std::string(kNoDeviceMessage) + " (USB cannot be used here: " + usb_error(s.init_error) + ")"};
  libusb_device** list = nullptr;
  const ssize_t count = libusb_get_device_list(s.context, &list);
  if (count < 0) return {TransportResult::failed, "3D mouse: the USB devices cannot be listed (" + usb_error(static_cast<int>(count)) + ")"};
  TransportStatus result{TransportResult::not_found, kNoDeviceMessage};
  for (ssize_t i = 0; i < count && result.result != TransportResult::ok; ++i) {
    libusb_device_descriptor d{};
    if (libusb_get_device_descriptor(list[i], &d) != 0 || !is_3dconnexion(d.idVendor, d.idProduct)) continue;
    const auto endpoint = hid_endpoint_in(list[i]);
    if (!endpoint) continue;
    TransportStatus tried = claim(s, list[i], *endpoint, d);
    // The first refusal says most; a later device that opens says more.
    if (tried.result == TransportResult::ok || result.result == TransportResult::not_found) result = std::move(tried);
  }
  libusb_free_device_list(list, 1);
  return result;
}

TransportStatus LibusbTransport::read(std::vector<std::uint8_t>& report, std::chrono::milliseconds timeout) {
  State& s = *m_state;
  if (!s.handle || s.departed) return {TransportResult::unplugged, ""};
  const int size = s.endpoint.packet_size > 0 ? s.endpoint.packet_size : 64;
  report.resize(static_cast<std::size_t>(size));
  int transferred = 0;
  // libusb waits forever on a timeout of 0.
  const unsigned int ms = static_cast<unsigned int>(std::max<std::chrono::milliseconds::rep>(1, timeout.count()));
  const int r = libusb_interrupt_transfer(s.handle, s.endpoint.address, report.data(), size, &transferred, ms);
  if (r == LIBUSB_SUCCESS || (r == LIBUSB_ERROR_TIMEOUT && transferred > 0)) {
    report.resize(static_cast<std::size_t>(transferred));
    return {TransportResult::ok, ""};
  }
  if (r == LIBUSB_ERROR_NO_DEVICE || s.departed) return {TransportResult::unplugged, ""};
  if (r == LIBUSB_ERROR_TIMEOUT) return {TransportResult::timeout, ""};
  return {TransportResult::failed, "3D mouse: reading failed (" + usb_error(r) + "); trying again"};
}

void LibusbTransport::close() {
  State& s = *m_state;
  if (!s.handle) return;
  libusb_release_interface(s.handle, s.endpoint.interface_number);
  libusb_close(s.handle);
  s.handle = nullptr;
  s.device = nullptr;
}

bool LibusbTransport::wait_for_arrival(std::chrono::milliseconds timeout) {
  State& s = *m_state;
  const auto deadline = Clock::now() + timeout;
  if (!s.context) {
    std::this_thread::sleep_until(deadline);
    return false;
  }
  if (!s.hotplug) {
    std::this_thread::sleep_until(std::min(deadline, s.next_poll));
    if (Clock::now() < s.next_poll) return false;
    s.next_poll = Clock::now() + kPollPeriod;
    return true;
  }
  for (auto now = Clock::now(); !s.arrived && now < deadline; now = Clock::now()) {
    timeval wait = as_timeval(deadline - now);
    libusb_handle_events_timeout_completed(s.context, &wait, &s.arrived);
  }
  const bool arrived = s.arrived != 0;
  s.arrived = 0;
  return arrived;
}

std::unique_ptr<SpaceMouseTransport> system_spacemouse_transport() { return std::make_unique<LibusbTransport>(); }

}  // namespace penumbra::viewer

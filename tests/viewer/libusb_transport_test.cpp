// SPDX-License-Identifier: BSD-3-Clause
// tests/viewer/libusb_transport_test.cpp -- the USB transport: which devices it takes, what its
// errors say, and, on a machine without a 3D mouse (or without USB), only "no 3D mouse found"
#include <gtest/gtest.h>
#include <libusb.h>

#include "libusb_transport.h"
#include "spacemouse_device.h"

namespace penumbra::viewer {
namespace {

using std::chrono::milliseconds;

TEST(SpaceMouseUsb, OnlyThe3DconnexionProducts) {
  EXPECT_TRUE(is_3dconnexion(0x256f, 0xc635));  // SpaceMouse Compact
  EXPECT_TRUE(is_3dconnexion(0x256f, 0xc652));  // universal receiver
  EXPECT_TRUE(is_3dconnexion(0x046d, 0xc626));  // SpaceNavigator
  EXPECT_TRUE(is_3dconnexion(0x046d, 0xc603));
  EXPECT_TRUE(is_3dconnexion(0x046d, 0xc640));
  EXPECT_FALSE(is_3dconnexion(0x046d, 0xc602));
  EXPECT_FALSE(is_3dconnexion(0x046d, 0xc641));
  EXPECT_FALSE(is_3dconnexion(0x046d, 0xc52b));  // Logitech's Unifying receiver
  EXPECT_FALSE(is_3dconnexion(0x1234, 0xc626));
}

TEST(SpaceMouseUsb, ErrorsSayWhatToDo) {
  const UsbLocation where{1, 5, 0x256f, 0xc635};
  const TransportStatus denied = open_failure(LIBUSB_ERROR_ACCESS, where);
  EXPECT_EQ(denied.result, TransportResult::access_denied);
  EXPECT_EQ(denied.message, "3D mouse: permission denied on bus 1 device 5 (256f:c635): see viewer/README.md for the udev rule");
  const TransportStatus gone = open_failure(LIBUSB_ERROR_NO_DEVICE, where);
  EXPECT_EQ(gone.result, TransportResult::not_found);
  EXPECT_EQ(gone.message, kNoDeviceMessage);
  const TransportStatus no_interface = open_failure(LIBUSB_ERROR_NOT_FOUND, where);
  EXPECT_EQ(no_interface.result, TransportResult::failed);
  EXPECT_NE(no_interface.message.find("bus 1 device 5"), std::string::npos);
  EXPECT_NE(no_interface.message.find("LIBUSB_ERROR_NOT_FOUND"), std::string::npos);
  EXPECT_NE(open_failure(LIBUSB_ERROR_BUSY, where).message.find("in use by another program"), std::string::npos);
}

TEST(SpaceMouseUsb, NoDeviceHereIsOnlyAStatus) {
  LibusbTransport usb;
  const TransportStatus opened = usb.open();
  if (opened.result == TransportResult::ok) GTEST_SKIP() << "a 3D mouse is attached: " << opened.message;
  EXPECT_NE(opened.message.find(kNoDeviceMessage), std::string::npos) << opened.message;
  std::vector<std::uint8_t> report;
  EXPECT_EQ(usb.read(report, milliseconds(10)).result, TransportResult::unplugged);
  const auto t0 = std::chrono::steady_clock::now();
  usb.wait_for_arrival(milliseconds(100));
  EXPECT_LT(std::chrono::steady_clock::now() - t0, std::chrono::seconds(2));
  usb.close();
}

TEST(SpaceMouseUsb, TheReaderOverUsbWaitsAndStops) {
  std::mutex mutex;
  std::condition_variable changed;
  std::string status;
  SpaceMouse mouse(system_spacemouse_transport(), SpaceMouseOptions{}, [](const ViewEvent&) {},
                   [&](const std::string& s) {
                     std::lock_guard<std::mutex> lock(mutex);
                     status = s;
                     changed.notify_all();
                   });
  mouse.start();
  std::unique_lock<std::mutex> lock(mutex);
  ASSERT_TRUE(changed.wait_for(lock, std::chrono::seconds(10), [&] { return !status.empty(); }));
  lock.unlock();
  if (status.rfind("3D mouse connected", 0) == 0) GTEST_SKIP() << status;
  EXPECT_NE(status.find(kNoDeviceMessage), std::string::npos) << status;
  mouse.stop();
}

}  // namespace
}  // namespace penumbra::viewer

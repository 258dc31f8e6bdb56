// SPDX-License-Identifier: BSD-3-Clause
// viewer/src/no_usb_transport.cpp -- penumbra-view built without libusb-1.0: no 3D mouse over USB
#include "spacemouse_transport.h"

namespace penumbra::viewer {

std::unique_ptr<SpaceMouseTransport> system_spacemouse_transport() { return nullptr; }

}  // namespace penumbra::viewer

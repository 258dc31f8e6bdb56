// SPDX-License-Identifier: BSD-3-Clause
// viewer/src/spacemouse_device.cpp -- the reader's loop: connect, read until unplugged, wait
#include "spacemouse_device.h"

#include <exception>

#include "spacemouse_report.h"

namespace penumbra::viewer {

SpaceMouse::SpaceMouse(std::unique_ptr<SpaceMouseTransport> transport, SpaceMouseOptions options, MotionHandler on_motion,
                       StatusHandler on_status)
    : m_transport(std::move(transport)),
      m_options(options),
      m_on_motion(std::move(on_motion)),
      m_on_status(std::move(on_status)) {}

SpaceMouse::~SpaceMouse() { stop(); }

void SpaceMouse::start() {
  if (m_thread.joinable() || !m_transport) return;
  m_stopping = false;
  m_thread = std::thread([this] { run(); });
}

void SpaceMouse::stop() {
  m_stopping = true;
  if (m_thread.joinable()) m_thread.join();
}

std::string SpaceMouse::status() const {
  std::lock_guard<std::mutex> lock(m_status_mutex);
  return m_status;
}

void SpaceMouse::set_status(const std::string& message) {
  {
    std::lock_guard<std::mutex> lock(m_status_mutex);
    if (message == m_status) return;
    m_status = message;
  }
  m_on_status(message);
}

// Whatever goes wrong on the reader's thread ends the reader, not the program.
void SpaceMouse::run() {
  std::string failure;
  try {
    loop();
  } catch (const std::exception& e) {
    failure = std::string("3D mouse stopped: ") + e.what();
  } catch (...) {
    failure = "3D mouse stopped: unknown error";
  }
  m_transport->close();
  if (failure.empty()) return;
  try {
    set_status(failure);
  } catch (...) {
  }
}

// A missing device is looked for again when one arrives; one that was refused (the udev rule may
// have been added since), or could not be opened or read for another reason (busy, a transfer
// error), is tried again after each arrival wait.
void SpaceMouse::loop() {
  bool look = true;
  while (!m_stopping) {
    TransportResult result = TransportResult::not_found;
    if (look) {
      result = connect();
      if (result == TransportResult::ok) {
        result = read_until_gone();
        m_transport->close();
      }
    }
    if (m_stopping) return;
    const bool arrived = m_transport->wait_for_arrival(m_options.arrival_wait);
    look = arrived || result == TransportResult::failed || result == TransportResult::access_denied;
  }
}

// "Unplugged" says more than "not found" while nothing has come back.
TransportResult SpaceMouse::connect() {
  const TransportStatus opened = m_transport->open();
  if (!(opened.result == TransportResult::not_found && status() == kUnpluggedMessage)) set_status(opened.message);
  return opened.result;
}

// Each report stands for the time since the previous one: the cap's position held that long.
TransportResult SpaceMouse::read_until_gone() {
  MotionState state;
  std::uint32_t held_buttons = 0;
  auto previous = std::chrono::steady_clock::now();
  std::vector<std::uint8_t> report;
  while (!m_stopping) {
    const TransportStatus got = m_transport->read(report, m_options.read_timeout);
    if (got.result == TransportResult::timeout) continue;
    if (got.result != TransportResult::ok) {
      set_status(got.result == TransportResult::unplugged ? kUnpluggedMessage : got.message);
      return got.result;
    }
    if (apply_report(report, state) == ReportKind::ignored) continue;
    const auto now = std::chrono::steady_clock::now();
    const ViewEvent event =
        map_motion(state, held_buttons, std::chrono::duration<double>(now - previous).count(), m_options.mapping);
    previous = now;
    held_buttons = state.buttons;
    if (!event.idle()) m_on_motion(event);
  }
  return TransportResult::ok;
}

}  // namespace penumbra::viewer

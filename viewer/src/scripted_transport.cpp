// SPDX-License-Identifier: BSD-3-Clause
// viewer/src/scripted_transport.cpp -- recorded reports played as a device, and their script
#include "scripted_transport.h"

#include <fstream>
#include <sstream>
#include <thread>

#include "penumbra/core/error.h"
#include "spacemouse_device.h"

namespace penumbra::viewer {
namespace {

constexpr long kMaxDelayMs = 60000;
constexpr std::size_t kMaxReportBytes = 64;

std::uint8_t hex_byte(const std::string& token, const std::string& where) {
  require(!token.empty() && token.size() <= 2 && token.find_first_not_of("0123456789abcdefABCDEF") == std::string::npos,
          where + ": '" + token + "' is not a byte in hexadecimal");
  return static_cast<std::uint8_t>(std::stoul(token, nullptr, 16));
}

std::chrono::milliseconds delay(const std::string& token, const std::string& where) {
  require(!token.empty() && token.size() <= 5 && token.find_first_not_of("0123456789") == std::string::npos &&
              std::stol(token) <= kMaxDelayMs,
          where + ": the delay '" + token + "' is not a number of milliseconds from 0 to 60000");
  return std::chrono::milliseconds(std::stol(token));
}

ScriptedReport scripted_report(const std::string& line, const std::string& where) {
  std::istringstream tokens(line);
  std::string token;
  tokens >> token;
  ScriptedReport report{delay(token, where), {}};
  while (tokens >> token) report.bytes.push_back(hex_byte(token, where));
  require(!report.bytes.empty() && report.bytes.size() <= kMaxReportBytes, where + ": a report has 1 to 64 bytes");
  return report;
}

}  // namespace

ScriptedTransport::ScriptedTransport(std::vector<ScriptedReport> reports, std::string name)
    : m_reports(std::move(reports)), m_name(std::move(name)) {}

void ScriptedTransport::plug_in() {
  {
    std::lock_guard<std::mutex> lock(m_mutex);
    m_plugged = true;
    m_arrived = true;
  }
  m_arrival.notify_all();
}

void ScriptedTransport::deny_access(bool deny) {
  std::lock_guard<std::mutex> lock(m_mutex);
  m_denied = deny;
}

int ScriptedTransport::times_opened() const {
  std::lock_guard<std::mutex> lock(m_mutex);
  return m_times_opened;
}

TransportStatus ScriptedTransport::open() {
  std::lock_guard<std::mutex> lock(m_mutex);
  if (!m_plugged) return {TransportResult::not_found, kNoDeviceMessage};
  if (m_denied)
    return {TransportResult::access_denied, "3D mouse: permission denied on " + m_name + ": see viewer/README.md for the udev rule"};
  m_open = true;
  ++m_times_opened;
  m_next = 0;
  m_due = std::chrono::steady_clock::now() + (m_reports.empty() ? std::chrono::milliseconds(0) : m_reports[0].delay);
  return {TransportResult::ok, "3D mouse connected: " + m_name};
}

TransportStatus ScriptedTransport::read(std::vector<std::uint8_t>& report, std::chrono::milliseconds timeout) {
  std::unique_lock<std::mutex> lock(m_mutex);
  if (!m_open || m_next == m_reports.size()) {
    m_plugged = false;
    return {TransportResult::unplugged, m_name + " unplugged"};
  }
  const auto due = m_due;
  lock.unlock();
  std::this_thread::sleep_until(std::min(due, std::chrono::steady_clock::now() + timeout));
  const auto now = std::chrono::steady_clock::now();
  if (now < due) return {TransportResult::timeout, ""};
  lock.lock();
  report = m_reports[m_next].bytes;
  if (++m_next < m_reports.size()) m_due = now + m_reports[m_next].delay;
  return {TransportResult::ok, ""};
}

void ScriptedTransport::close() {
  std::lock_guard<std::mutex> lock(m_mutex);
  m_open = false;
}

bool ScriptedTransport::wait_for_arrival(std::chrono::milliseconds timeout) {
  std::unique_lock<std::mutex> lock(m_mutex);
  m_arrival.wait_for(lock, timeout, [this] { return m_arrived; });
  const bool arrived = m_arrived;
  m_arrived = false;
  return arrived;
}

std::vector<ScriptedReport> read_report_script(std::istream& in, const std::string& name) {
  std::vector<ScriptedReport> reports;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    line = line.substr(0, line.find('#'));
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    reports.push_back(scripted_report(line, name + " line " + std::to_string(number)));
  }
  return reports;
}

std::vector<ScriptedReport> read_report_script_file(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) throw Error(ErrorCode::io_error, "penumbra-view: cannot read the report script '" + path.string() + "'");
  return read_report_script(in, path.string());
}

}  // namespace penumbra::viewer

// SPDX-License-Identifier: BSD-3-Clause
// viewer/src/scripted_transport.h -- a 3D mouse that plays recorded reports: the tests' device,
// and penumbra-view's --spacemouse-script
#pragma once
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <filesystem>
#include <istream>
#include <mutex>
#include <string>
#include <vector>

#include "spacemouse_transport.h"

namespace penumbra::viewer {

struct ScriptedReport {
  std::chrono::milliseconds delay{0};  ///< after the previous report, or after the device was opened
  std::vector<std::uint8_t> bytes;     ///< the report, its id first
};

/// Absent until plug_in(); once opened, yields its reports, each after its delay, then unplugs.
/// plug_in() again brings it back, from its first report. While deny_access(true) holds, open()
/// answers as a device without the udev rule does.
class ScriptedTransport : public SpaceMouseTransport {
public:
  explicit ScriptedTransport(std::vector<ScriptedReport> reports, std::string name = "scripted 3D mouse");

  /// A hotplug arrival; from any thread.
  void plug_in();
  void deny_access(bool deny);
  /// How many times open() has succeeded.
  int times_opened() const;

  TransportStatus open() override;
  TransportStatus read(std::vector<std::uint8_t>& report, std::chrono::milliseconds timeout) override;
  void close() override;
  bool wait_for_arrival(std::chrono::milliseconds timeout) override;

private:
  const std::vector<ScriptedReport> m_reports;
  const std::string m_name;
  mutable std::mutex m_mutex;
  std::condition_variable m_arrival;
  bool m_plugged = false;
  bool m_arrived = false;
  bool m_open = false;
  bool m_denied = false;
  int m_times_opened = 0;
  std::size_t m_next = 0;
  std::chrono::steady_clock::time_point m_due;
};

/// A report script: one report a line, `DELAY_MS BYTE...`, the delay in milliseconds (0 to
/// 60000) after the previous report, then 1 to 64 bytes in hexadecimal; `#` starts a comment.
/// Throws penumbra::Error(invalid_argument) naming `name` and the line.
std::vector<ScriptedReport> read_report_script(std::istream& in, const std::string& name);
/// The same from a file; throws penumbra::Error(io_error) when it cannot be read.
std::vector<ScriptedReport> read_report_script_file(const std::filesystem::path& path);

}  // namespace penumbra::viewer

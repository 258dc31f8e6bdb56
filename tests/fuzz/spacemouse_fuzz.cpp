// SPDX-License-Identifier: BSD-3-Clause
// tests/fuzz/spacemouse_fuzz.cpp -- penumbra-view's 3D mouse input: the reports a USB device
// sends (apply_report) and the view changes made of them (map_motion), and report scripts
// (read_report_script). Bytes starting with '#' are a script; any other bytes are a sequence of
// reports, each a length byte and that many bytes. A report that is ignored leaves the motion
// state as it was; every view change is finite and within the rates' bounds; a script gives
// reports or a penumbra::Error.
#include <cmath>
#include <cstdint>
#include <span>
#include <sstream>
#include <string>

#include "fuzz_util.h"
#include "scripted_transport.h"
#include "spacemouse_mapping.h"
#include "spacemouse_report.h"

namespace {

using namespace penumbra::viewer;

bool same(const MotionState& a, const MotionState& b) {
  return a.translation == b.translation && a.rotation == b.rotation && a.buttons == b.buttons;
}

void check_event(const ViewEvent& e, double sensitivity) {
  const double seconds = kMaxReportSeconds * sensitivity;
  const bool bounded = std::abs(e.d_phi) <= kOrbitDegreesPerSecond * seconds && std::abs(e.d_theta) <= kOrbitDegreesPerSecond * seconds &&
                       std::abs(e.d_time) <= kTimeStepsPerSecond * seconds && e.zoom > 0 &&
                       std::abs(std::log2(e.zoom)) <= kZoomDoublingsPerSecond * seconds + 1e-12;
  if (!bounded) penumbra::fuzz::fail("map_motion gave a view change beyond the rates' bounds");
}

void reports(std::span<const std::uint8_t> bytes) {
  MotionState state;
  std::uint32_t held = 0;
  const MappingSettings settings[] = {{1.0, 15}, {10.0, 0}, {0.1, 349}};
  for (std::size_t at = 0; at < bytes.size();) {
    const std::size_t length = std::min<std::size_t>(bytes[at], bytes.size() - at - 1);
    const MotionState before = state;
    if (apply_report(bytes.subspan(at + 1, length), state) == ReportKind::ignored && !same(before, state))
      penumbra::fuzz::fail("an ignored report changed the motion state");
    for (const MappingSettings& s : settings) check_event(map_motion(state, held, 0.01 * (at % 7), s), s.sensitivity);
    held = state.buttons;
    at += 1 + length;
  }
}

void script(const std::string& text) {
  std::istringstream in(text);
  try {
    for (const ScriptedReport& r : read_report_script(in, "fuzz"))
      if (r.bytes.empty() || r.bytes.size() > 64 || r.delay.count() < 0 || r.delay.count() > 60000)
        penumbra::fuzz::fail("read_report_script gave a report out of its bounds");
  } catch (const penumbra::Error& e) {
    penumbra::fuzz::expect_code(e, penumbra::ErrorCode::invalid_argument, "read_report_script");
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size > 0 && data[0] == '#')
    script(std::string(reinterpret_cast<const char*>(data), size));
  else
    reports(std::span<const std::uint8_t>(data, size));
  return 0;
}

// SPDX-License-Identifier: BSD-3-Clause
// viewer/src/spacemouse_report.cpp -- the two 3Dconnexion report layouts, told apart by length
#include "spacemouse_report.h"

#include <algorithm>

namespace penumbra::viewer {
namespace {

constexpr std::uint8_t kMotionId = 1;
constexpr std::uint8_t kRotationId = 2;
constexpr std::uint8_t kButtonsId = 3;
constexpr std::size_t kAxesReportSize = 1 + 3 * 2;
constexpr std::size_t kCombinedReportSize = 1 + 6 * 2;

std::int16_t int16_le(const std::uint8_t* bytes) {
  return static_cast<std::int16_t>(static_cast<std::uint16_t>(bytes[0] | (bytes[1] << 8)));
}

std::array<std::int16_t, 3> three_axes(const std::uint8_t* bytes) {
  return {int16_le(bytes), int16_le(bytes + 2), int16_le(bytes + 4)};
}

std::uint32_t bitmask_le(std::span<const std::uint8_t> bytes) {
  std::uint32_t mask = 0;
  const std::size_t n = std::min<std::size_t>(bytes.size(), 4);
  for (std::size_t i = 0; i < n; ++i) mask |= static_cast<std::uint32_t>(bytes[i]) << (8 * i);
  return mask;
}

}  // namespace

ReportKind apply_report(std::span<const std::uint8_t> report, MotionState& state) {
  if (report.empty()) return ReportKind::ignored;
  const std::uint8_t* axes = report.data() + 1;
  switch (report[0]) {
    case kMotionId:
      if (report.size() >= kCombinedReportSize) {
        state.translation = three_axes(axes);
        state.rotation = three_axes(axes + 6);
        return ReportKind::motion;
      }
      if (report.size() < kAxesReportSize) return ReportKind::ignored;
      state.translation = three_axes(axes);
      return ReportKind::translation;
    case kRotationId:
      if (report.size() < kAxesReportSize) return ReportKind::ignored;
      state.rotation = three_axes(axes);
      return ReportKind::rotation;
    case kButtonsId:
      if (report.size() < 2) return ReportKind::ignored;
      state.buttons = bitmask_le(report.subspan(1));
      return ReportKind::buttons;
    default:
      return ReportKind::ignored;
  }
}

}  // namespace penumbra::viewer

// SPDX-License-Identifier: BSD-3-Clause
// viewer/src/spacemouse_report.h -- a 3Dconnexion device's HID interrupt reports, as motion
#pragma once
#include <array>
#include <cstdint>
#include <span>

namespace penumbra::viewer {

/// Where the cap is: its displacement along and about the device's axes (HID convention: x to
/// the right, y towards the user, z down; rotations right-handed about those axes), and which
/// buttons are held (bit i: button i + 1).
struct MotionState {
  std::array<std::int16_t, 3> translation{};  ///< x, y, z
  std::array<std::int16_t, 3> rotation{};     ///< rx, ry, rz
  std::uint32_t buttons = 0;
};

/// What one report carried.
enum class ReportKind { ignored, translation, rotation, motion, buttons };

/// Applies one interrupt report (its first byte the report id) to `state`. The two layouts are
/// told apart by length, since both use id 1 and the vendor id does not say which a device sends:
///   - older devices: id 1 with 3 little-endian int16 (translation, 7 bytes), id 2 likewise
///     (rotation), id 3 with the buttons as a little-endian bitmask in the bytes after the id;
///   - newer devices: id 1 with 6 little-endian int16, translation then rotation (13 bytes);
///     buttons as id 3.
/// A report too short for its id, or of another id, leaves `state` as it was (ReportKind::ignored).
/// Buttons beyond the 32nd are dropped.
ReportKind apply_report(std::span<const std::uint8_t> report, MotionState& state);

}  // namespace penumbra::viewer

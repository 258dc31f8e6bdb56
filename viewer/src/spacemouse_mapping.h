// SPDX-License-Identifier: BSD-3-Clause
// viewer/src/spacemouse_mapping.h -- where the 3D mouse's cap is, as a change of the page's view
#pragma once
#include <cstdint>

#include "spacemouse_report.h"

namespace penumbra::viewer {

/// A change of the view the page shows. Rates are per second of the cap held, so a device that
/// sends more reports does not turn the view faster.
struct ViewEvent {
  double d_phi = 0;    ///< degrees; negative is what dragging the image to the right does
  double d_theta = 0;  ///< degrees; positive is what dragging the image down does
  double zoom = 1;     ///< factor on the image's scale; above 1 nearer
  double d_time = 0;   ///< time steps, fractional: the page moves by whole ones as they add up
  bool reset_view = false;   ///< button 1 went down: back to the first view, unzoomed
  bool toggle_play = false;  ///< button 2 went down: play or pause time
  bool idle() const;
};

struct MappingSettings {
  double sensitivity = 1.0;  ///< multiplies every rate; (0, 10]
  int dead_zone = 15;        ///< device units; a smaller displacement counts as none; [0, 350)
};

/// The displacement that counts as full (current devices report about ±350); more is clamped.
inline constexpr int kFullDeflection = 350;
/// At full deflection and sensitivity 1.
inline constexpr double kOrbitDegreesPerSecond = 90;
inline constexpr double kTimeStepsPerSecond = 8;
inline constexpr double kZoomDoublingsPerSecond = 1;
/// The longest time one report stands for: a longer gap means the cap was at rest.
inline constexpr double kMaxReportSeconds = 0.05;

/// Throws penumbra::Error(invalid_argument) naming the option when a setting is out of range.
void check_settings(const MappingSettings& settings);

/// A displacement as a fraction of full deflection in [-1, 1]: zero inside the dead zone, then
/// growing from zero at its edge, so that leaving the dead zone does not jump.
double deflection(int value, int dead_zone);

/// The view change for the cap held at `state` for `seconds` (clamped to kMaxReportSeconds):
/// twist (rz) orbits in phi, turning clockwise seen from above as dragging to the right does;
/// tilt (rx) orbits in theta, tilting towards the user as dragging down does; sliding right (x)
/// moves time forward; pushing down (z) zooms in. Buttons act when they go down, that is, when
/// set in `state` and not in `previous_buttons`.
ViewEvent map_motion(const MotionState& state, std::uint32_t previous_buttons, double seconds,
                     const MappingSettings& settings);

}  // namespace penumbra::viewer

// SPDX-License-Identifier: BSD-3-Clause
// viewer/src/spacemouse_mapping.cpp -- dead zone, sensitivity, axes to orbit, time and zoom
#include "spacemouse_mapping.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <sstream>
#include <string>

#include "penumbra/core/error.h"

namespace penumbra::viewer {
namespace {

constexpr std::uint32_t kResetButton = 1u << 0;
constexpr std::uint32_t kPlayButton = 1u << 1;

}  // namespace

bool ViewEvent::idle() const {
  return d_phi == 0 && d_theta == 0 && zoom == 1 && d_time == 0 && !reset_view && !toggle_play;
}

void check_settings(const MappingSettings& settings) {
  std::ostringstream sensitivity;
  sensitivity << settings.sensitivity;
  require(std::isfinite(settings.sensitivity) && settings.sensitivity > 0 && settings.sensitivity <= 10,
          "penumbra-view --spacemouse-sensitivity: " + sensitivity.str() + " is not in (0, 10]");
  require(settings.dead_zone >= 0 && settings.dead_zone < kFullDeflection,
          "penumbra-view --spacemouse-deadzone: " + std::to_string(settings.dead_zone) + " is not in [0, " +
              std::to_string(kFullDeflection) + ")");
}

double deflection(int value, int dead_zone) {
  const int beyond = std::abs(value) - dead_zone;
  if (beyond <= 0) return 0;
  const double fraction = std::min(1.0, static_cast<double>(beyond) / (kFullDeflection - dead_zone));
  return value < 0 ? -fraction : fraction;
}

ViewEvent map_motion(const MotionState& state, std::uint32_t previous_buttons, double seconds,
                     const MappingSettings& settings) {
  const double dt = std::clamp(seconds, 0.0, kMaxReportSeconds) * settings.sensitivity;
  const auto axis = [&](std::int16_t value) { return deflection(value, settings.dead_zone) * dt; };
  ViewEvent event;
  event.d_phi = -kOrbitDegreesPerSecond * axis(state.rotation[2]);
  event.d_theta = kOrbitDegreesPerSecond * axis(state.rotation[0]);
  event.d_time = kTimeStepsPerSecond * axis(state.translation[0]);
  event.zoom = std::exp2(kZoomDoublingsPerSecond * axis(state.translation[2]));
  const std::uint32_t pressed = state.buttons & ~previous_buttons;
  event.reset_view = (pressed & kResetButton) != 0;
  event.toggle_play = (pressed & kPlayButton) != 0;
  return event;
}

}  // namespace penumbra::viewer

// SPDX-License-Identifier: BSD-3-Clause
// insitu/src/step_budget.cpp -- the degradation order of a step over its budget
#include "step_budget.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace penumbra::insitu {
namespace {

/// Below 16 nodes on its longest axis level 0 no longer resolves a shadow's edge across the mesh.
constexpr int kMinLevel0 = 16;
/// Images are rendered down to a quarter of their width and height, in steps of 1/16.
constexpr double kMinImageScale = 0.25;
constexpr double kImageScaleStep = 1.0 / 16;

/// The light's part of a plan: its allowance, and the level-0 resolution it runs at.
struct LightPlan {
  int level0 = 0;
  double allowance = -1;  ///< negative: not capped
  double least_ms = 0;    ///< what it takes at least (one piece), whatever its allowance
};

/// Steps 1 and 2: the light carried over (capped at what is left after the images), then level 0
/// coarsened until a piece fits. A coarsened level 0 comes back up while twice its resolution
/// fits whole, judged by a measured level-0 solve (a converged light's small update says nothing
/// of what a volume made again costs). Solve costs go with the cube of the resolution; a step
/// that solved no level 0 (piece 0) gives no reason to coarsen it.
LightPlan plan_light(double allow, const StepCosts& costs, int level0, int level0_now) {
  LightPlan p;
  p.level0 = level0_now;
  double need = costs.light_converged ? costs.light_ms : 2 * costs.light_ms;
  double piece = costs.light_piece_ms;
  while (p.level0 < level0 && piece > 0 && std::max(need, piece) * 8 <= allow) {
    p.level0 = std::min(level0, 2 * p.level0);
    need *= 8;
    piece *= 8;
  }
  if (need <= allow) return p;
  while (piece > 0 && piece > allow && p.level0 > kMinLevel0) {
    p.level0 = std::max(kMinLevel0, p.level0 / 2);
    need /= 8;
    piece /= 8;
  }
  if (need <= allow) return p;
  p.allowance = std::max(allow, 0.0);
  p.least_ms = std::min(piece, need);
  return p;
}

}  // namespace

std::string Degradation::text() const {
  std::string t;
  const auto add = [&t](const std::string& part) { t += (t.empty() ? "" : "+") + part; };
  if (light) add("light");
  if (level0_resolution > 0) add("level0:" + std::to_string(level0_resolution));
  if (image_scale < 1.0) {
    std::ostringstream scale;
    scale << image_scale;  // a multiple of 1/16: at most 4 decimals
    add("image:" + scale.str());
  }
  if (cameras_reduced()) add("cameras:" + std::to_string(cameras) + "/" + std::to_string(cameras_configured));
  return t.empty() ? "none" : t;
}

StepPlan plan_step(double budget_ms, const StepCosts& costs, int cameras, int images_per_camera, std::size_t pixels,
                   int level0, int level0_now) {
  StepPlan plan;
  plan.light_piece_ms = costs.light_piece_ms;
  Degradation& d = plan.degradation;
  d.cameras = d.cameras_configured = cameras;
  const double images = static_cast<double>(cameras) * images_per_camera;
  const double render_full = costs.render_ms_per_pixel * static_cast<double>(pixels);
  double least_light = 0;
  if (level0_now > 0) {
    const LightPlan light = plan_light(budget_ms - costs.fixed_ms - images * (render_full + costs.image_ms), costs, level0,
                                       level0_now);
    if (light.level0 < level0) d.level0_resolution = light.level0;
    plan.light_ms = light.allowance;
    least_light = light.least_ms;
    if (light.allowance < 0) return plan;  // the light fits whole, and so do the images
  }
  // Step 3: the images smaller, each rendered at scale^2 of its pixels.
  const double room = budget_ms - costs.fixed_ms - least_light;
  const double render_room = room - images * costs.image_ms;
  if (render_full <= 0 || images * render_full <= render_room) return plan;
  const double fitting = render_room > 0 ? std::sqrt(render_room / (images * render_full)) : 0;
  d.image_scale = std::max(kMinImageScale, std::floor(fitting / kImageScaleStep) * kImageScaleStep);
  if (fitting >= kMinImageScale) return plan;
  // Step 4: fewer cameras, each at the smallest images.
  const double per_camera = images_per_camera * (render_full * kMinImageScale * kMinImageScale + costs.image_ms);
  const double fit = per_camera > 0 ? std::floor(room / per_camera) : cameras;
  d.cameras = static_cast<int>(std::clamp(fit, 1.0, static_cast<double>(cameras)));
  return plan;
}

}  // namespace penumbra::insitu

// SPDX-License-Identifier: BSD-3-Clause
// insitu/src/step_budget.h -- what a rendering step gives up to stay within its time budget
#pragma once
#include <cstddef>
#include <optional>
#include <string>

namespace penumbra::insitu {

/// "budget": the most time one rendering step may take: `ms`, and/or `share` of the solver's own
/// time per step (measured between its pnb_execute calls); with both, the smaller. 0 = unused.
struct BudgetConfig {
  double ms = 0;
  double share = 0;
};

/// What a step gave up, in the order it is given up (insitu/README.md, "budget"):
/// 1. light: the light volume stopped short of converged; it goes on converging over the next
///    steps, each starting from the last;
/// 2. level 0: the light volume's level-0 grid at a lower resolution;
/// 3. image: the images rendered at a fraction of the configured width and height, then enlarged
///    to it (the database keeps one image size);
/// 4. cameras: only some cameras rendered, the next ones on the next step, so every camera is
///    refreshed in turn.
struct Degradation {
  bool light = false;
  int level0_resolution = 0;  ///< the reduced resolution; 0 = as configured
  double image_scale = 1.0;
  int cameras = 0, cameras_configured = 0;  ///< rendered of configured; equal when not degraded

  bool cameras_reduced() const { return cameras < cameras_configured; }
  bool any() const { return light || level0_resolution > 0 || image_scale < 1.0 || cameras_reduced(); }
  /// The database's `degraded` value: "none", or the degradations joined by '+', e.g.
  /// "light+level0:64+image:0.5+cameras:2/8".
  std::string text() const;
};

/// A step's measured costs (the last rendering step's, the largest over ranks), per unit of what
/// the plan can change.
struct StepCosts {
  double fixed_ms = 0;            ///< store, gather and the rest: what no degradation changes
  double light_ms = 0;            ///< the light's whole last update (0 without a light volume)
  bool light_converged = true;    ///< whether that update converged (else light_ms fell short)
  double light_piece_ms = 0;      ///< its largest indivisible piece: a level-0 solve of one light
  double render_ms_per_pixel = 0; ///< ray casting per rendered pixel
  double image_ms = 0;            ///< compositing and writing per image (at the configured size)
};

/// What a step is to do, and what it gives up for it.
struct StepPlan {
  Degradation degradation;
  double light_ms = -1;        ///< the light's allowance; negative: as lighting.budget says
  double light_piece_ms = 0;   ///< the piece it was planned with (costs.light_piece_ms)
};

/// Plans one step within `budget_ms` from `costs`. `images_per_camera` is the number of fields;
/// `pixels` the configured image's; `level0` the configured level-0 resolution and `level0_now`
/// the one in use (0: no light volume). The light's last cost is that of a full update only when it
/// converged; otherwise it needed more, taken as twice as much.
StepPlan plan_step(double budget_ms, const StepCosts& costs, int cameras, int images_per_camera, std::size_t pixels,
                   int level0, int level0_now);

}  // namespace penumbra::insitu

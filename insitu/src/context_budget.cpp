// SPDX-License-Identifier: BSD-3-Clause
// insitu/src/context_budget.cpp -- a Context's steps kept within their "budget" (step_budget.h)
#include <algorithm>
#include <cmath>
#include <limits>

#include "context.h"
#include "prepared_mesh.h"

namespace penumbra::insitu {
namespace {

double median(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

bool light_volume_model(const Config& c) {
  return c.lighting && !c.lighting->occlusion_model && c.lighting->model == render::LightingModel::light_volume;
}

/// What `s` (the last rendering step) says a step costs. Lighting other than the light volume's
/// is not degraded by steps 1 and 2: its time counts as fixed.
StepCosts costs_of(const StepStats& s, bool light_volume) {
  StepCosts c;
  c.fixed_ms = s.store_ms + s.gather_ms + s.other_ms + (light_volume ? 0 : s.light_ms);
  if (light_volume) {
    c.light_ms = s.light_ms;
    c.light_converged = s.light_converged;
    c.light_piece_ms = s.light_piece_ms;
  }
  c.render_ms_per_pixel = s.rendered_pixels > 0 ? s.render_ms / s.rendered_pixels : 0;
  c.image_ms = s.views > 0 ? (s.composite_ms + s.write_ms) / s.views : 0;
  return c;
}

}  // namespace

double Context::budget_for_step(bool renders) {
  if (!m_config.budget || !renders) return 0;
  const BudgetConfig& b = *m_config.budget;
  double ms = b.ms > 0 ? b.ms : std::numeric_limits<double>::infinity();
  if (b.share > 0 && !m_solver_step_ms.empty()) ms = std::min(ms, b.share * median(m_solver_step_ms));
  m_decisions->minimum(&ms, 1);
  // A share alone, before the solver's time per step is known: the step measures, unbounded.
  return std::isfinite(ms) ? ms : 0;
}

std::optional<StepPlan> Context::plan_this_step(double budget_ms) {
  if (budget_ms <= 0) return std::nullopt;  // the same on every rank (budget_for_step)
  const bool light_volume = light_volume_model(m_config);
  StepCosts c = costs_of(m_last_step, light_volume);
  // Every rank plans from the largest costs, so that all plan alike (minimum of the negatives),
  // and only once every rank has measured a step: a rank whose last step failed early has not.
  double v[8] = {-c.fixed_ms, -c.light_ms, -c.light_piece_ms, -c.render_ms_per_pixel, -c.image_ms,
                 c.light_converged ? 1.0 : 0.0, -budget_ms, m_last_step.views > 0 ? 1.0 : 0.0};
  m_group->minimum(v, 8);
  if (v[7] == 0) return std::nullopt;
  c = {-v[0], -v[1], v[5] > 0, -v[2], -v[3], -v[4]};
  int level0 = 0, level0_now = 0;
  if (light_volume) {
    level0 = m_config.lighting->level0_resolution;
    const auto& volumes = m_mesh->light_volumes;
    level0_now = !volumes.empty() && volumes[0] ? volumes[0]->options().level0_resolution : level0;
  }
  return plan_step(-v[6], c, static_cast<int>(m_mesh->cameras.size()), static_cast<int>(m_config.fields.size()),
                   static_cast<std::size_t>(m_config.width) * m_config.height, level0, level0_now);
}

std::vector<std::size_t> Context::step_cameras() {
  const std::size_t all = m_mesh->cameras.size();
  const std::size_t n = m_plan ? static_cast<std::size_t>(m_plan->degradation.cameras) : all;
  std::vector<std::size_t> cameras;
  if (n >= all) {
    for (std::size_t c = 0; c < all; ++c) cameras.push_back(c);
    return cameras;
  }
  // In turn, and in the configured order, so that every camera is refreshed every all / n steps.
  for (std::size_t k = 0; k < n; ++k) cameras.push_back((m_next_camera + k) % all);
  m_next_camera = (m_next_camera + n) % all;
  std::sort(cameras.begin(), cameras.end());
  return cameras;
}

render::LightBudget Context::light_budget() const {
  render::LightBudget budget = m_config.lighting->budget;
  if (!m_plan || m_plan->light_ms < 0) return budget;
  const double share = m_plan->light_ms / static_cast<double>(m_config.fields.size());
  if (m_group->size() > 1) {
    // Over ranks in whole pieces, the largest rank's, so that every rank does the same work.
    const double piece = std::max(m_plan->light_piece_ms, 1e-3);
    const int units = std::max(1, static_cast<int>(share / piece));
    budget.max_work_units = budget.max_work_units < 0 ? units : std::min(budget.max_work_units, units);
  } else {
    budget.max_ms = std::min(budget.max_ms, share);
  }
  return budget;
}

void Context::note_light_update(std::size_t index) {
  const render::LightUpdateReport& r = m_last_step.light;
  if (r.lights_recomputed > 0)
    m_last_step.light_piece_ms = std::max(m_last_step.light_piece_ms, r.l0_prop_ms / r.lights_recomputed);
  bool converged = r.converged;
  if (m_plan && m_group->size() > 1) {
    double v = converged ? 1.0 : 0.0;
    m_group->minimum(&v, 1);
    converged = v > 0;
  }
  m_last_step.light_converged = m_last_step.light_converged && converged;
  if (m_plan && m_plan->light_ms >= 0 && !converged) m_light_short[index] = true;
}

Degradation Context::step_degradation() const {
  if (!m_plan) {
    Degradation none;
    none.cameras = none.cameras_configured = static_cast<int>(m_mesh->cameras.size());
    return none;
  }
  Degradation d = m_plan->degradation;
  d.light = std::find(m_light_short.begin(), m_light_short.end(), true) != m_light_short.end();
  return d;
}

render::Camera Context::step_camera(std::size_t camera) const {
  render::Camera c = m_mesh->cameras[camera].camera;
  if (!m_plan || m_plan->degradation.image_scale >= 1) return c;
  const double s = m_plan->degradation.image_scale;
  c.width = std::max(1, static_cast<int>(std::lround(c.width * s)));
  c.height = std::max(1, static_cast<int>(std::lround(c.height * s)));
  return c;
}

}  // namespace penumbra::insitu

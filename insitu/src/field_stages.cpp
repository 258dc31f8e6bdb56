// SPDX-License-Identifier: BSD-3-Clause
// insitu/src/field_stages.cpp
#include "field_stages.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "penumbra/core/field_view.h"

namespace penumbra::insitu {

std::string lighting_label(const LightingConfig& l) {
  if (l.occlusion_model) return "occlusion";
  switch (l.model) {
    case render::LightingModel::none: return "none";
    case render::LightingModel::phong: return "phong";
    case render::LightingModel::light_volume: return "light-volume";
  }
  return "none";
}

bool lit(const Config& c) { return c.lighting && c.lighting->model != render::LightingModel::none; }

render::Shading shading_of(const LightingConfig& l, const std::vector<float>* light_rgb) {
  render::Shading s;
  s.model = l.model;
  s.light_rgb = light_rgb;
  s.ambient = l.ambient;
  s.diffuse = l.diffuse;
  s.specular = l.specular;
  s.shininess = l.shininess;
  // The key light for the diffuse and specular terms: the first directional light, seen from
  // the lit side (towards the light); a headlight when there is none.
  for (const render::Light& light : l.lights)
    if (light.kind == render::Light::Kind::directional) {
      s.light_direction = -normalize(light.vector);
      break;
    }
  return s;
}

std::vector<std::string> field_labels(const Config& c) {
  std::vector<std::string> labels;
  for (const auto& f : c.fields) {
    int uses = 0;
    for (const auto& g : c.fields) uses += g.name == f.name;
    if (uses == 1) labels.push_back(f.name);
    else if (f.mode == ComponentMode::magnitude) labels.push_back(f.name + "_magnitude");
    else labels.push_back(f.name + "_c" + std::to_string(f.component));
  }
  return labels;
}

std::pair<double, double> local_range(const FieldConfig& f, const std::vector<double>& values) {
  if (f.range) return *f.range;
  const ValueRange r = finite_range(values);
  if (r.finite_count == 0) return {HUGE_VAL, -HUGE_VAL};
  return {r.lo, r.hi};
}

std::pair<double, double> usable_range(double lo, double hi) {
  if (hi > lo) return {lo, hi};
  // The value sits inside instead of dividing by zero. Any half-width works; this one is at least
  // the value's own size, and an end beyond the largest double is held at it.
  if (lo > hi) lo = 0;  // no finite value anywhere
  const double h = 0.5 * std::max(1.0, std::fabs(lo)), largest = std::numeric_limits<double>::max();
  return {std::max(lo - h, -largest), std::min(lo + h, largest)};
}

render::TransferFunction resolve_transfer_function(const FieldConfig& f, double lo, double hi, double diagonal) {
  render::TransferFunction tf = f.transfer_function;
  if (f.x_units == XUnits::data) tf.normalize_x(lo, hi);
  if (f.opacity_unit == OpacityUnit::diagonal && diagonal > 0)
    for (auto& o : tf.opacities) o.a /= diagonal;
  return tf;
}

}  // namespace penumbra::insitu

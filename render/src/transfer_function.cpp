// SPDX-License-Identifier: BSD-3-Clause
// render/src/transfer_function.cpp -- piecewise-linear colour and extinction
#include "penumbra/render/transfer_function.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "penumbra/core/error.h"
#include "penumbra/core/field_view.h"

namespace penumbra::render {
namespace {

// Linear interpolation of `value(p)` over points sorted by x, clamped beyond the ends.
template <class P, class F>
auto interpolate(const std::vector<P>& points, double s, F value) {
  if (s <= points.front().x) return value(points.front());
  if (s >= points.back().x) return value(points.back());
  const auto hi = std::upper_bound(points.begin(), points.end(), s, [](double v, const P& p) { return v < p.x; });
  const auto lo = hi - 1;
  const double w = (hi->x > lo->x) ? (s - lo->x) / (hi->x - lo->x) : 1.0;
  return value(*lo) * (1.0 - w) + value(*hi) * w;
}

}  // namespace

Vec3d TransferFunction::color(double s) const {
  if (colors.empty() || std::isnan(s)) return {0, 0, 0};
  return interpolate(colors, s, [](const ColorPoint& p) { return Vec3d{p.r, p.g, p.b}; });
}

double TransferFunction::extinction(double s) const {
  if (opacities.empty() || std::isnan(s)) return 0.0;
  return interpolate(opacities, s, [](const OpacityPoint& p) { return p.a; });
}

std::vector<double> TransferFunction::breakpoints() const {
  std::vector<double> x;
  x.reserve(colors.size() + opacities.size());
  for (const auto& p : colors) x.push_back(p.x);
  for (const auto& p : opacities) x.push_back(p.x);
  std::sort(x.begin(), x.end());
  x.erase(std::unique(x.begin(), x.end()), x.end());
  return x;
}

void TransferFunction::normalize_x(double lo, double hi) {
  for (auto& c : colors) c.x = normalize_value(c.x, lo, hi);
  for (auto& o : opacities) o.x = normalize_value(o.x, lo, hi);
}

void TransferFunction::validate() const {
  const std::string call = "TransferFunction::validate: ";
  require(!colors.empty(), call + "colors is empty; expected at least one colour point");
  require(!opacities.empty(), call + "opacities is empty; expected at least one opacity point");
  for (std::size_t i = 0; i < colors.size(); ++i) {
    const auto& p = colors[i];
    const std::string at = "colors[" + std::to_string(i) + "]";
    require(std::isfinite(p.x) && std::isfinite(p.r) && std::isfinite(p.g) && std::isfinite(p.b),
            call + at + " is not finite; expected finite x, r, g, b");
    require(p.r >= 0 && p.g >= 0 && p.b >= 0, call + at + " has a negative channel; expected r, g, b >= 0");
    require(i == 0 || p.x >= colors[i - 1].x,
            call + at + ".x = " + std::to_string(p.x) + " is smaller than the previous point's; expected sorted x");
  }
  for (std::size_t i = 0; i < opacities.size(); ++i) {
    const auto& p = opacities[i];
    const std::string at = "opacities[" + std::to_string(i) + "]";
    require(std::isfinite(p.x) && std::isfinite(p.a), call + at + " is not finite; expected finite x and a");
    require(p.a >= 0, call + at + ".a = " + std::to_string(p.a) + "; expected an extinction >= 0");
    require(i == 0 || p.x >= opacities[i - 1].x,
            call + at + ".x = " + std::to_string(p.x) + " is smaller than the previous point's; expected sorted x");
  }
}

}  // namespace penumbra::render

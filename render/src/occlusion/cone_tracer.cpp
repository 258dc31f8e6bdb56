// SPDX-License-Identifier: BSD-3-Clause
// render/src/occlusion/cone_tracer.cpp -- Gaussian cone tracing (thesis sec. 3.2.2-3.2.4, app. A)
//
// The sample schedule (distance, level and blend, cone count, trapezoid weight, section weight) depends only
// on the options and sigma0, so it is built once, like the thesis's 1D texture; tracing a cone
// then costs one trilinear fetch per sample and sub-cone, two where it blends two levels.
#include <algorithm>
#include <cmath>
#include <string>

#include "penumbra/core/error.h"
#include "occlusion/occlusion_internals.h"
#include "shader_constants.h"

namespace penumbra::render {
namespace {

constexpr double kPi = 3.14159265358979323846;
// "Circle packing in a circle" (thesis fig. 3.5): 3 circles of radius 1 / (1 + 2 / sqrt 3) with
// centres at 1 - that radius; 7 circles of radius 1/3, one central and six with centres at 2/3.
const double kRadius3 = 1.0 / (1.0 + 2.0 / std::sqrt(3.0));
const double kOffset3 = 1.0 - kRadius3;
constexpr double kRadius7 = 1.0 / 3.0;
constexpr double kOffset7 = 2.0 / 3.0;
using shader::kOpaqueDepth;     // shared with cone_trace.comp
using shader::kSaturatedDepth;

double section_weight(SectionWeight model, double r, double sigma, double alpha) {
  if (model == SectionWeight::mean) return alpha;
  // eq. 3-15: (p_r sigma sqrt(2 pi))^2 / (pi r^2), p_r = erf(r / (sigma sqrt 2)); r -> 0 gives 4/pi.
  const double x = r / (sigma * std::sqrt(2.0));
  if (x < 1e-6) return alpha * 4.0 / kPi;
  const double p = std::erf(x);
  return alpha * (p * p * 2.0 * kPi * sigma * sigma) / (kPi * r * r);
}

// ln(1 + x) / x for x = V / mu: exp(-mu times it) is the mean of exp(-D) over a gamma-distributed
// D with mean mu and variance V. 1 (plain exp(-mu)) when there is no variance.
double gamma_depth_factor(double variance, double mean) {
  if (!(variance > 0) || !(mean > 0)) return 1.0;
  const double x = variance / mean;
  return std::log1p(x) / x;
}

double sub_tan(int cones, double tan_theta) {
  return cones == 1 ? tan_theta : (cones == 3 ? tan_theta * kRadius3 : tan_theta * kRadius7);
}

void frame(const Vec3d& w, Vec3d& u, Vec3d& v) {
  // The switch sits at an irrational |w.x| (the golden ratio's inverse), which no axis between
  // round coordinates hits, so the float GPU path (cone_trace.comp) picks the same helper.
  const Vec3d helper = std::fabs(w.x) < 0.6180339887498949 ? Vec3d{1, 0, 0} : Vec3d{0, 1, 0};
  u = normalize(cross(helper, w));
  v = cross(w, u);
}

}  // namespace

ConeTracer::ConeTracer(const ExtinctionPyramid& pyramid, const ConeOptions& options)
    : m_pyramid(&pyramid), m_options(options) {
  require(pyramid.levels() >= 1, "ConeTracer: the extinction pyramid is empty");
  const ConeOptions& o = options;
  require(std::isfinite(o.aperture_deg) && o.aperture_deg > 0 && o.aperture_deg <= 89,
          "ConeTracer: aperture_deg = " + std::to_string(o.aperture_deg) + "; expected in (0, 89]");
  require(o.splits == 1 || o.splits == 3 || o.splits == 7,
          "ConeTracer: splits = " + std::to_string(o.splits) + "; expected 1, 3 or 7");
  require(std::isfinite(o.length) && o.length >= 0, "ConeTracer: length = " + std::to_string(o.length) + "; expected >= 0");
  require(std::isfinite(o.fraction_of_diagonal) && o.fraction_of_diagonal > 0,
          "ConeTracer: fraction_of_diagonal = " + std::to_string(o.fraction_of_diagonal) + "; expected > 0");
  require(std::isfinite(o.gap), "ConeTracer: gap is not finite");
  require(std::isfinite(o.attenuation) && o.attenuation > 0,
          "ConeTracer: attenuation = " + std::to_string(o.attenuation) + "; expected > 0");

  const double sigma0 = pyramid.sigma0();
  m_length = o.length > 0 ? o.length : o.fraction_of_diagonal * pyramid.bounds().diagonal();
  m_gap = o.gap >= 0 ? o.gap : 3.0 * sigma0;
  const double tan_theta = std::tan(o.aperture_deg * kPi / 180.0);

  for (int k = 0; k < 3; ++k) {
    const double phi = (30.0 + 120.0 * k) * kPi / 180.0;
    m_dir3[static_cast<std::size_t>(k)] = normalize(Vec3d{tan_theta * kOffset3 * std::cos(phi), tan_theta * kOffset3 * std::sin(phi), 1.0});
  }
  m_dir7[0] = {0, 0, 1};
  for (int j = 0; j < 6; ++j) {
    const double phi = 60.0 * j * kPi / 180.0;
    m_dir7[static_cast<std::size_t>(j + 1)] = normalize(Vec3d{tan_theta * kOffset7 * std::cos(phi), tan_theta * kOffset7 * std::sin(phi), 1.0});
  }

  // Schedule: at each distance, split first while the section outgrows r_c = 2 sigma0 (keeps
  // level 0 as long as possible), then read the continuous level lambda = log2(r / (2 sigma0)),
  // sigma_lambda = sigma0 2^lambda = r / 2 -- the per-axis standard deviation of a uniform disc of
  // radius r, so the filter has the section's second moment (docs/cone_tracing.md, "Level selection") --
  // blending the two levels around it. Steps are 2.5 sigma_lambda. LevelSelection::thesis rounds
  // lambda up to a whole level instead.
  if (!(m_length > m_gap)) return;
  const int top = pyramid.levels() - 1;
  int cones = 1;
  double d = m_gap, prev_d = m_gap;
  for (bool first = true;; first = false) {
    while (cones < o.splits && d * sub_tan(cones, tan_theta) > 2.0 * sigma0) cones = cones == 1 ? 3 : 7;
    const double r = d * sub_tan(cones, tan_theta);
    double lambda = std::min(static_cast<double>(top), r > 2.0 * sigma0 ? std::log2(r / (2.0 * sigma0)) : 0.0);
    // The thesis's whole level: the finest l with r <= 2 sigma_l (a hair of tolerance so that
    // r = 2 sigma_l exactly stays on l despite rounding in log2).
    if (o.level == LevelSelection::thesis) lambda = std::ceil(lambda - 1e-9);
    int level = static_cast<int>(std::floor(lambda));
    double blend = lambda - level;
    if (level >= top) level = top, blend = 0.0;
    double sigma = sigma0 * std::exp2(lambda);
    if (o.unfiltered_grid && o.level == LevelSelection::continuous && r < 2.0 * sigma0 && pyramid.fine().sigma < sigma0) {
      // Narrower than level 0's filter: the unfiltered grid, blended toward level 0 linearly in
      // log2 sigma (docs/cone_tracing.md, "Below level 0").
      const double fine = pyramid.fine().sigma;
      const double lambda_fine = std::log2(fine / sigma0);
      const double want = std::max(fine, 0.5 * r);
      level = kFineLevel;
      blend = (std::log2(want / sigma0) - lambda_fine) / -lambda_fine;
      sigma = want;
    }
    m_schedule.push_back({d, first ? 0.0 : 0.5 * (d - prev_d), section_weight(o.weight, r, sigma, o.attenuation), level, cones, blend});
    if (d >= m_length) break;
    prev_d = d;
    // The last sample sits exactly at L (trapezoid over [h0, L]).
    d = std::min(m_length, d + kConeStepSigmas * sigma);
  }
}

double ConeTracer::transmittance(const Vec3d& apex, const Vec3d& axis) const {
  return transmittance(apex, axis, m_length);
}

double ConeTracer::transmittance(const Vec3d& apex, const Vec3d& axis, double max_length) const {
  const double len = penumbra::length(axis);
  if (!(len > 0) || !std::isfinite(len) || m_schedule.empty() || !(max_length > m_gap)) return 1.0;
  const Vec3d w = axis / len;
  Vec3d u, v;
  frame(w, u, v);
  auto world = [&](const Vec3d& c) { return u * c.x + v * c.y + w * c.z; };
  Vec3d dirs[7];
  double depth[7] = {0, 0, 0, 0, 0, 0, 0}, amp[7] = {0, 0, 0, 0, 0, 0, 0};
  int cones = 1;
  dirs[0] = w;
  for (std::size_t s = 0; s < m_schedule.size(); ++s) {
    ConeSample cs = m_schedule[s];
    bool last = false;
    if (cs.distance >= max_length) {
      // Stop at the target (a point light): one shortened trapezoid to max_length.
      const double prev = s > 0 ? m_schedule[s - 1].distance : cs.distance;
      cs.weight = s > 0 ? 0.5 * (max_length - prev) : 0.0;
      cs.distance = max_length;
      last = true;
    }
    if (cs.cones != cones) {
      if (cs.cones == 3 && cones == 1) {
        // 1 -> 3: every sub-cone inherits the parent (Algorithm 3, lines 2-4).
        for (int i = 1; i < 3; ++i) depth[i] = depth[0], amp[i] = amp[0];
      } else {
        if (cones == 1)
          for (int i = 1; i < 3; ++i) depth[i] = depth[0], amp[i] = amp[0];
        // 3 -> 7: centre takes the mean of the three, border cones 2k+1, 2k+2 the closest
        // 3-cone k (Algorithm 4, lines 2-11).
        const double d3[3] = {depth[0], depth[1], depth[2]}, a3[3] = {amp[0], amp[1], amp[2]};
        depth[0] = (d3[0] + d3[1] + d3[2]) / 3.0;
        amp[0] = (a3[0] + a3[1] + a3[2]) / 3.0;
        for (int k = 0; k < 3; ++k)
          for (int j = 0; j < 2; ++j) depth[1 + 2 * k + j] = d3[k], amp[1 + 2 * k + j] = a3[k];
      }
      cones = cs.cones;
      for (int i = 0; i < cones; ++i)
        dirs[i] = world(cones == 3 ? m_dir3[static_cast<std::size_t>(i)] : m_dir7[static_cast<std::size_t>(i)]);
    }
    const PyramidLevel& lev = cs.level == kFineLevel ? m_pyramid->fine() : m_pyramid->level(cs.level);
    const PyramidLevel& next = cs.blend > 0 ? m_pyramid->level(cs.level + 1) : lev;
    bool all_opaque = true;
    for (int i = 0; i < cones; ++i) {
      const Vec3d x = apex + dirs[i] * cs.distance;
      double tau = lev.sample(x);
      if (cs.blend > 0) tau += cs.blend * (next.sample(x) - tau);
      const double a = cs.kappa * tau;
      depth[i] += cs.weight * (amp[i] + a);
      amp[i] = a;
      all_opaque = all_opaque && depth[i] > kOpaqueDepth;
    }
    if (last || all_opaque) break;
  }
  // Variance within each final cone from the spread between them (docs/cone_tracing.md, "Lateral
  // variance").
  double within = 0;
  if (cones > 1) {
    // Depths beyond kSaturatedDepth let nothing through whatever their value, so they enter the
    // spread clamped: how deep an opaque sub-cone's depth runs says nothing about its neighbours.
    double mean = 0, spread = 0, clamped[7];
    for (int i = 0; i < cones; ++i) mean += clamped[i] = std::min(depth[i], kSaturatedDepth);
    mean /= cones;
    for (int i = 0; i < cones; ++i) spread += (clamped[i] - mean) * (clamped[i] - mean);
    within = lateral_variance_ratio(cones) * spread / cones;
  }
  // Cosine-weighted mean over the final cones (thesis Algorithm 4, line 27).
  double sum = 0, wsum = 0;
  for (int i = 0; i < cones; ++i) {
    const double c = cones == 1 ? 1.0 : dot(dirs[i], w);
    sum += c * std::exp(-depth[i] * gamma_depth_factor(within, depth[i]));
    wsum += c;
  }
  return sum / wsum;
}

double ConeTracer::lateral_variance_ratio(int cones) const {
  if (!m_options.lateral_variance || cones == 1) return 0.0;
  return cones == 3 ? kRadius3 * kRadius3 / (2.0 * kOffset3 * kOffset3)
                    : kRadius7 * kRadius7 / 4.0 / (6.0 / 7.0 * kOffset7 * kOffset7 / 2.0);
}

}  // namespace penumbra::render

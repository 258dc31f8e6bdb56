// SPDX-License-Identifier: BSD-3-Clause
// render/src/occlusion/cone_monte_carlo.cpp -- ground truth for one cone (thesis eq. 3-6, 3-7)
//
// Directions are cosine-weighted within the aperture: sin^2(angle) uniform in [0, sin^2 theta]
// and the azimuth uniform, so the plain mean of the transmittances is eq. 3-6's cosine-weighted
// average. Each ray's optical depth over [h0, L] is exact (LightTransmittanceReference: every
// tet on the segment, double precision, cut at transfer-function breakpoints), so the only error
// is the sampling. The points come from the R2 low-discrepancy sequence with a seeded random
// shift; K doubles until the estimates at K and K/2 differ by less than the tolerance.
#include <cmath>
#include <random>
#include <string>

#include "penumbra/core/error.h"
#include "penumbra/render/light_volume.h"
#include "occlusion/occlusion_internals.h"

namespace penumbra::render {

struct ConeMonteCarlo::Impl {
  std::shared_ptr<const TetMesh> mesh;
  std::vector<float> scalars;
  TransferFunction tf;
  std::unique_ptr<LightTransmittanceReference> reference;
};

ConeMonteCarlo::ConeMonteCarlo(std::shared_ptr<const TetMesh> mesh, const std::vector<float>& point_scalars,
                               const TransferFunction& tf)
    : m_impl(std::make_unique<Impl>()) {
  require(mesh != nullptr, "ConeMonteCarlo: mesh is null");
  require(point_scalars.size() == mesh->points.size(), "ConeMonteCarlo: " + std::to_string(point_scalars.size()) +
                                                            " scalars for " + std::to_string(mesh->points.size()) +
                                                            " points; expected one per point");
  tf.validate();
  m_impl->scalars = point_scalars;
  m_impl->tf = tf;
  m_impl->reference = std::make_unique<LightTransmittanceReference>(mesh);
  m_impl->mesh = std::move(mesh);
}

ConeMonteCarlo::~ConeMonteCarlo() = default;

MonteCarloResult ConeMonteCarlo::transmittance(const Vec3d& apex, const Vec3d& axis, double aperture_deg, double gap,
                                               double length_, double tolerance, int min_rays, int max_rays,
                                               std::uint64_t seed) const {
  constexpr double kPi = 3.14159265358979323846;
  require(std::isfinite(aperture_deg) && aperture_deg > 0 && aperture_deg < 90,
          "ConeMonteCarlo: aperture_deg = " + std::to_string(aperture_deg) + "; expected in (0, 90)");
  require(std::isfinite(gap) && gap >= 0 && std::isfinite(length_), "ConeMonteCarlo: gap and length must be finite, gap >= 0");
  require(min_rays >= 1 && max_rays >= min_rays, "ConeMonteCarlo: expected 1 <= min_rays <= max_rays");
  require(tolerance > 0, "ConeMonteCarlo: tolerance must be > 0");
  const double alen = penumbra::length(axis);
  require(alen > 0 && std::isfinite(alen), "ConeMonteCarlo: axis must be finite and non-zero");
  MonteCarloResult result;
  if (!(length_ > gap)) {
    result.transmittance = 1.0;
    result.converged = true;
    return result;
  }
  const Vec3d w = axis / alen;
  const Vec3d helper = std::fabs(w.x) < 0.6 ? Vec3d{1, 0, 0} : Vec3d{0, 1, 0};
  const Vec3d u = normalize(cross(helper, w)), v = cross(w, u);
  const double sin2 = std::pow(std::sin(aperture_deg * kPi / 180.0), 2);

  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  const double shift[2] = {uni(rng), uni(rng)};
  // R2 sequence: the plastic number's reciprocals give the most uniform 2D additive recurrence.
  const double g = 1.32471795724474602596;
  const double a1 = 1.0 / g, a2 = 1.0 / (g * g);
  auto ray = [&](long i) {
    const double s1 = std::fmod(shift[0] + a1 * static_cast<double>(i), 1.0);
    const double s2 = std::fmod(shift[1] + a2 * static_cast<double>(i), 1.0);
    const double sin_t = std::sqrt(s1 * sin2), cos_t = std::sqrt(1.0 - s1 * sin2);
    const double psi = 2.0 * kPi * s2;
    const Vec3d d = w * cos_t + u * (sin_t * std::cos(psi)) + v * (sin_t * std::sin(psi));
    const Light end{Light::Kind::point, apex + d * length_, {1, 1, 1}};
    return std::exp(-m_impl->reference->optical_depth(m_impl->scalars, m_impl->tf, end, apex + d * gap));
  };
  double sum = 0;
  long k = 0;
  double previous = -1;
  for (long target = min_rays;; target *= 2) {
    for (; k < target; ++k) sum += ray(k);
    const double estimate = sum / static_cast<double>(k);
    result.transmittance = estimate;
    result.rays = static_cast<int>(k);
    if (previous >= 0) {
      result.standard_error = std::fabs(estimate - previous);
      if (result.standard_error < tolerance) {
        result.converged = true;
        break;
      }
    }
    previous = estimate;
    if (target * 2 > max_rays) break;
  }
  return result;
}

}  // namespace penumbra::render

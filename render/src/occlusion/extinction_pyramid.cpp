// SPDX-License-Identifier: BSD-3-Clause
// render/src/occlusion/extinction_pyramid.cpp -- Gaussian mip pyramid of extinction
//
// Every level is a lattice lo + n * spacing_l (spacing_l = 2^l spacing of the grid), n running
// over the grid's extent plus a margin of P = ceil(3 sigma0 / spacing) nodes per side, so the
// blur that leaks past the mesh bounds is stored instead of cut (sigma_l / spacing_l is the same
// on every level, so P is too). Filtering is separable; taps beyond the input are zeros, and each
// kernel is normalised by its full sum, so values near the bounds fall off like the true
// convolution of tau with 0 outside (never clamp-to-edge, which would invent extinction there).
//
// Mass at the bounds. The grid's first and last nodes along each axis lie on the mesh bounds, and
// the mesh ends there: such a node stands for half a cell of medium, not a whole one. Filtered
// at full weight it puts tau h / 2 of extra optical depth on every ray that leaves through a
// face of the bounds, and trilinear interpolation between it and the zero padding does the same
// within a spacing beyond the face. So the filters weigh those nodes by 1/2 per axis (separably:
// each pass halves the ends of its own axis), and the unfiltered grid reads 0 beyond its nodes
// (docs/cone_tracing.md, "Mass at the bounds").
#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>

#include "penumbra/core/error.h"
#include "penumbra/core/thread_pool.h"
#include "occlusion/occlusion_internals.h"
#include "pyramid_filter_taps.h"

namespace penumbra::render {
namespace {

// One separable pass along `axis`: out[o] = sum_k w[k] in[stride * o + offset + k] (zero beyond
// the input). The other two axes keep their sizes. halve_ends: the input's first and last node
// along the axis count half (see "Mass at the bounds" above).
std::vector<float> filter_axis(const std::vector<float>& in, const std::array<int, 3>& in_dims, int axis, int out_count,
                               int stride, int offset, double sigma_nodes, bool halve_ends, std::array<int, 3>& out_dims) {
  int radius = 0;
  const std::vector<double> w = detail::gaussian_taps(sigma_nodes, radius);
  out_dims = in_dims;
  out_dims[axis] = out_count;
  const int a1 = axis == 0 ? 1 : 0, a2 = axis == 2 ? 1 : 2;
  std::size_t in_step[3] = {1, static_cast<std::size_t>(in_dims[0]), static_cast<std::size_t>(in_dims[0]) * in_dims[1]};
  std::size_t out_step[3] = {1, static_cast<std::size_t>(out_dims[0]), static_cast<std::size_t>(out_dims[0]) * out_dims[1]};
  std::vector<float> out(static_cast<std::size_t>(out_dims[0]) * out_dims[1] * out_dims[2], 0.0f);
  const int n_in = in_dims[axis];
  const std::size_t lines = static_cast<std::size_t>(in_dims[a1]) * in_dims[a2];
  parallel_for(lines, 64, [&](std::size_t l0, std::size_t l1) {
    for (std::size_t l = l0; l < l1; ++l) {
      const std::size_t c1 = l % static_cast<std::size_t>(in_dims[a1]), c2 = l / static_cast<std::size_t>(in_dims[a1]);
      const std::size_t in_base = c1 * in_step[a1] + c2 * in_step[a2];
      const std::size_t out_base = c1 * out_step[a1] + c2 * out_step[a2];
      for (int o = 0; o < out_count; ++o) {
        const int centre = stride * o + offset;
        const int k0 = std::max(-radius, -centre), k1 = std::min(radius, n_in - 1 - centre);
        double sum = 0;
        for (int k = k0; k <= k1; ++k) {
          const int i = centre + k;
          const double end = halve_ends && (i == 0 || i == n_in - 1) ? 0.5 : 1.0;
          sum += end * w[static_cast<std::size_t>(k + radius)] * in[in_base + static_cast<std::size_t>(i) * in_step[axis]];
        }
        out[out_base + static_cast<std::size_t>(o) * out_step[axis]] = static_cast<float>(sum);
      }
    }
  });
  return out;
}

std::vector<float> to_opacity(const std::vector<float>& tau, double l) {
  std::vector<float> a(tau.size());
  for (std::size_t i = 0; i < tau.size(); ++i)
    a[i] = static_cast<float>(std::min(detail::kMaxOpacity, -std::expm1(-static_cast<double>(tau[i]) * l)));
  return a;
}

std::vector<float> to_extinction(const std::vector<float>& opacity, double l) {
  std::vector<float> t(opacity.size());
  for (std::size_t i = 0; i < opacity.size(); ++i) {
    const double a = std::clamp(static_cast<double>(opacity[i]), 0.0, detail::kMaxOpacity);
    t[i] = static_cast<float>(-std::log1p(-a) / l);
  }
  return t;
}

}  // namespace

double PyramidLevel::sample(const Vec3d& p) const {
  int i[3];
  double f[3];
  for (int a = 0; a < 3; ++a) {
    const double u = (p[a] - lo[a]) / spacing[a];
    if (!(u > -1.0 && u < dims[a])) return 0.0;  // also rejects NaN
    if (empty_beyond_nodes && (u < 0.0 || u > dims[a] - 1)) return 0.0;
    const double fl = std::floor(u);
    i[a] = static_cast<int>(fl);
    f[a] = u - fl;
  }
  double sum = 0;
  for (int corner = 0; corner < 8; ++corner) {
    int c[3];
    double w = 1;
    bool inside = true;
    for (int a = 0; a < 3; ++a) {
      const int d = (corner >> a) & 1;
      c[a] = i[a] + d;
      w *= d ? f[a] : 1.0 - f[a];
      inside = inside && c[a] >= 0 && c[a] < dims[a];
    }
    if (inside && w > 0)
      sum += w * tau[static_cast<std::size_t>(c[0]) +
                     static_cast<std::size_t>(dims[0]) * (static_cast<std::size_t>(c[1]) + static_cast<std::size_t>(dims[1]) * c[2])];
  }
  return sum;
}

ExtinctionPyramid::ExtinctionPyramid(const ExtinctionGrid& grid, const PyramidOptions& options) {
  grid.validate("ExtinctionPyramid");
  require(std::isfinite(options.sigma0) && options.sigma0 >= 0,
          "ExtinctionPyramid: sigma0 = " + std::to_string(options.sigma0) + "; expected finite >= 0 (0 = mean spacing)");
  require(options.max_levels >= 1, "ExtinctionPyramid: max_levels = " + std::to_string(options.max_levels) + "; expected >= 1");
  const auto t0 = std::chrono::steady_clock::now();
  const double sigma0 = options.sigma0 > 0 ? options.sigma0 : grid.mean_spacing();
  m_bounds.lo = grid.lo;
  for (int a = 0; a < 3; ++a) m_bounds.hi[a] = grid.lo[a] + (grid.dims[a] - 1) * grid.spacing[a];

  int pad[3];
  double sigma_nodes0[3];
  for (int a = 0; a < 3; ++a) {
    sigma_nodes0[a] = sigma0 / grid.spacing[a];
    pad[a] = static_cast<int>(std::ceil(3.0 * sigma_nodes0[a]));
  }

  // Level l's lattice: nodes lo + (n - pad) spacing_l, spacing_l = 2^l spacing; interior node
  // counts halve per level, N_{l+1} = ceil(N_l / 2), until at most 2 per axis.
  int interior[3] = {grid.dims[0] - 1, grid.dims[1] - 1, grid.dims[2] - 1};
  auto make_level = [&](int l, const std::array<int, 3>& dims, std::vector<float> tau) {
    PyramidLevel level;
    level.dims = dims;
    level.spacing = grid.spacing * std::ldexp(1.0, l);
    for (int a = 0; a < 3; ++a) level.lo[a] = grid.lo[a] - pad[a] * level.spacing[a];
    level.sigma = sigma0 * std::ldexp(1.0, l);
    level.tau = std::move(tau);
    m_levels.push_back(std::move(level));
  };
  auto more_levels = [&] {
    if (static_cast<int>(m_levels.size()) >= options.max_levels) return false;
    if (m_levels.empty()) return true;
    if (std::max(interior[0], std::max(interior[1], interior[2])) <= 2) return false;
    for (int a = 0; a < 3; ++a) interior[a] = (interior[a] + 1) / 2;
    return true;
  };

  if (options.quantity == PyramidQuantity::step_opacity) {
    // Every level from the grid itself: the opacity of a slab as thick as the level's cone step,
    // filtered with sigma_l at stride 2^l, converted back with the same thickness (the levels
    // cannot be chained: the thickness changes per level).
    for (int l = 0; more_levels(); ++l) {
      const int stride = 1 << l;
      const double thickness = kConeStepSigmas * sigma0 * stride;
      std::vector<float> data = to_opacity(grid.tau, thickness);
      std::array<int, 3> dims = grid.dims;
      for (int a = 0; a < 3; ++a) {
        std::array<int, 3> out_dims{};
        data = filter_axis(data, dims, a, interior[a] + 1 + 2 * pad[a], stride, -pad[a] * stride, stride * sigma_nodes0[a],
                           true, out_dims);
        dims = out_dims;
      }
      make_level(l, dims, to_extinction(data, thickness));
    }
  } else {
    // Extinction, or per-cell opacity (converted back to extinction per level): level 0 is the
    // grid convolved with sigma0 on the padded lattice; level l+1 is level l (in the filtered
    // quantity) convolved with sqrt(3) sigma_l (variances add: 4 = 1 + 3), kept at every second
    // node (output node o reads input index 2 o - pad).
    const bool opacity = options.quantity == PyramidQuantity::opacity;
    const double cell = grid.mean_spacing();
    std::vector<float> data = opacity ? to_opacity(grid.tau, cell) : grid.tau;
    std::array<int, 3> dims = grid.dims;
    for (int l = 0; more_levels(); ++l) {
      for (int a = 0; a < 3; ++a) {
        std::array<int, 3> out_dims{};
        data = l == 0 ? filter_axis(data, dims, a, interior[a] + 1 + 2 * pad[a], 1, -pad[a], sigma_nodes0[a], true, out_dims)
                      : filter_axis(data, dims, a, interior[a] + 1 + 2 * pad[a], 2, -pad[a], std::sqrt(3.0) * sigma_nodes0[a],
                                    false, out_dims);
        dims = out_dims;
      }
      make_level(l, dims, opacity ? to_extinction(data, cell) : data);
    }
  }
  m_fine.dims = grid.dims;
  m_fine.lo = grid.lo;
  m_fine.spacing = grid.spacing;
  m_fine.sigma = grid.mean_spacing() / std::sqrt(6.0);
  m_fine.tau = grid.tau;
  m_fine.empty_beyond_nodes = true;
  m_build_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace penumbra::render

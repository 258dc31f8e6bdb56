// SPDX-License-Identifier: BSD-3-Clause
// render/src/reference_renderer.cpp -- double-precision ground truth, independent of adjacency
//
// Per ray: every tet the ray crosses is found (a BVH over all tets for images, all tets for a
// single trace), the ray is clipped against the tet's four face half-spaces, the intervals are
// sorted, and each interval is integrated by adaptive Gauss-Kronrod (7/15) quadrature of the
// emission c(s) tau(s) exp(-depth) after cutting it where the scalar crosses a breakpoint of
// the transfer function (where the integrand has kinks). Nothing here shares code with the
// walk or the closed-form segment integral, so the two can check each other.
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "bvh.h"
#include "tet_clip.h"
#include "penumbra/core/error.h"
#include "render_inputs.h"
#include "penumbra/core/thread_pool.h"
#include "penumbra/render/cpu_ray_caster.h"

namespace penumbra::render {
namespace {

struct Interval {
  double t0, t1;
  std::int32_t tet;
  bool operator<(const Interval& o) const { return t0 < o.t0 || (t0 == o.t0 && t1 < o.t1); }
};

// The ray as a clip line (unit direction).
struct RefRay : detail::ClipLine {
  explicit RefRay(const Ray& ray) : detail::ClipLine(ray.origin, normalize(ray.direction)) {}
};

bool clip(const TetMesh& mesh, std::int32_t t, const RefRay& r, Interval& out) {
  double lo = 0, hi = 0;
  if (!detail::clip_to_tet(mesh, t, r, std::numeric_limits<double>::infinity(), lo, hi)) return false;
  out = {lo, hi, t};
  return true;
}

struct Accum {
  double rgb[3] = {0, 0, 0};
  double transmittance = 1, optical_depth = 0;
};

// Emission of one smooth piece of length `len` where the scalar runs linearly sa -> sb:
// integral of c tau exp(-depth) with depth exactly (tau_a + tau(x)) x / 2 (tau is linear here).
struct Piece {
  const TransferFunction& tf;
  double sa, sb, len, tau_a;
  void eval(double x, double out[3]) const {
    const double s = sa + (sb - sa) * (x / len);
    const double tau = tf.extinction(s);
    const Vec3d c = tf.color(s);
    const double w = tau * std::exp(-0.5 * (tau_a + tau) * x);
    out[0] = c.x * w;
    out[1] = c.y * w;
    out[2] = c.z * w;
  }
};

constexpr double kXgk[8] = {0.991455371120812639206854697526329, 0.949107912342758524526189684047851,
                            0.864864423359769072789712788640926, 0.741531185599394439863864773280788,
                            0.586087235467691130294144845693013, 0.405845151377397166906606412076961,
                            0.207784955007898467600689403773245, 0.0};
constexpr double kWgk[8] = {0.022935322010529224963732008058970, 0.063092092629978553290700663189204,
                            0.104790010322250183839876322541518, 0.140653259715525918745189590510238,
                            0.169004726639267902826583426598550, 0.190350578064785409913256402421014,
                            0.204432940075298892414161999234649, 0.209482141084727828012999174891714};
constexpr double kWg[4] = {0.129484966168869693270611432679082, 0.279705391489276667901467771423780,
                           0.381830050505118944950369775488975, 0.417959183673469387755102040816327};

// Adaptive Gauss-Kronrod 7/15 on [x0, x1], accepted when |K15 - G7| <= 1e-10 |K15| + 1e-14 (x1 - x0) / len:
// both terms are colours (no unit), so the test does not depend on the world's length unit.
void integrate_gk(const Piece& p, double x0, double x1, int depth, double out[3]) {
  const double c = 0.5 * (x0 + x1), h = 0.5 * (x1 - x0);
  double k[3] = {0, 0, 0}, g[3] = {0, 0, 0}, f[3];
  for (int i = 0; i < 8; ++i) {
    const int signs = i == 7 ? 1 : 2;
    for (int sgn = 0; sgn < signs; ++sgn) {
      p.eval(c + (sgn ? -h : h) * kXgk[i], f);
      for (int ch = 0; ch < 3; ++ch) {
        k[ch] += kWgk[i] * f[ch];
        if (i % 2 == 1) g[ch] += kWg[i / 2] * f[ch];
      }
    }
  }
  double err = 0, mag = 0;
  for (int ch = 0; ch < 3; ++ch) {
    k[ch] *= h;
    g[ch] *= h;
    err = std::max(err, std::fabs(k[ch] - g[ch]));
    mag = std::max(mag, std::fabs(k[ch]));
  }
  if (err <= 1e-10 * mag + 1e-14 * (x1 - x0) / p.len || depth >= 40) {
    for (int ch = 0; ch < 3; ++ch) out[ch] += k[ch];
    return;
  }
  integrate_gk(p, x0, c, depth + 1, out);
  integrate_gk(p, c, x1, depth + 1, out);
}

// Integrates the interval of `len` with scalars s0 -> s1 onto acc.
void integrate_interval(const TransferFunction& tf, const std::vector<double>& breaks, double s0, double s1, double len,
                        Accum& acc) {
  if (std::isnan(s0) || std::isnan(s1) || !(len > 0)) return;
  // Cut points (fractions of the interval) where the scalar crosses a breakpoint.
  double cuts[66];
  int n = 0;
  cuts[n++] = 0.0;
  for (double x : breaks) {
    if (n >= 64) break;
    if ((x > s0 && x < s1) || (x < s0 && x > s1)) cuts[n++] = (x - s0) / (s1 - s0);
  }
  cuts[n++] = 1.0;
  std::sort(cuts, cuts + n);
  for (int i = 0; i + 1 < n; ++i) {
    const double fa = cuts[i], fb = cuts[i + 1];
    const double plen = (fb - fa) * len;
    if (!(plen > 0)) continue;
    const double sa = s0 + (s1 - s0) * fa, sb = s0 + (s1 - s0) * fb;
    // Extinction at the piece's ends, extrapolated from inside: exact for the linear piece and
    // blind to a step (repeated control point x) sitting on a cut.
    const double q1 = tf.extinction(0.75 * sa + 0.25 * sb), q3 = tf.extinction(0.25 * sa + 0.75 * sb);
    const double tau_a = std::max(0.0, 1.5 * q1 - 0.5 * q3), tau_b = std::max(0.0, 1.5 * q3 - 0.5 * q1);
    const Piece piece{tf, sa, sb, plen, tau_a};
    double e[3] = {0, 0, 0};
    if (tau_a > 0 || tau_b > 0) integrate_gk(piece, 0.0, plen, 0, e);
    const double depth = 0.5 * (tau_a + tau_b) * plen;
    for (int ch = 0; ch < 3; ++ch) acc.rgb[ch] += acc.transmittance * e[ch];
    acc.transmittance *= std::exp(-depth);
    acc.optical_depth += depth;
  }
}

RayTrace integrate_intervals(const TetMesh& mesh, const std::vector<float>& scalars, const TransferFunction& tf,
                             const std::vector<double>& breaks, const RefRay& r, std::vector<Interval>& iv) {
  std::sort(iv.begin(), iv.end());
  Accum acc;
  RayTrace out;
  // Runs of intervals separated by gaps are entries; runs shorter than `graze` (rounding-size
  // touches of the boundary) are not counted, as in the fast renderer.
  const double gap = 1e-9 * mesh.bounds.diagonal(), graze = 1e-12 * mesh.bounds.diagonal();
  double last_end = -std::numeric_limits<double>::infinity(), run_length = 0;
  for (const Interval& i : iv) {
    const double s0 = detail::scalar_in_tet(mesh, scalars, i.tet, r.o + r.d * i.t0);
    const double s1 = detail::scalar_in_tet(mesh, scalars, i.tet, r.o + r.d * i.t1);
    integrate_interval(tf, breaks, s0, s1, i.t1 - i.t0, acc);
    if (i.t0 > last_end + gap) {
      out.entries += run_length > graze;
      run_length = 0;
    }
    last_end = std::max(last_end, i.t1);
    run_length += i.t1 - i.t0;
    out.length_inside += i.t1 - i.t0;
    ++out.segments;
  }
  out.entries += run_length > graze;
  for (int c = 0; c < 3; ++c) out.rgba[c] = acc.rgb[c];
  out.rgba[3] = 1.0 - acc.transmittance;
  out.optical_depth = acc.optical_depth;
  return out;
}

}  // namespace

RayTrace trace_reference(const TetMesh& mesh, const std::vector<float>& scalars, const TransferFunction& tf,
                         const Ray& ray) {
  detail::check_render_inputs("trace_reference", mesh, scalars, tf);
  const RefRay r(ray);
  std::vector<Interval> iv;
  Interval i{};
  for (std::size_t t = 0; t < mesh.tets.size(); ++t)
    if (clip(mesh, static_cast<std::int32_t>(t), r, i)) iv.push_back(i);
  return integrate_intervals(mesh, scalars, tf, tf.breakpoints(), r, iv);
}

Image render_reference(const TetMesh& mesh, const std::vector<float>& scalars, const TransferFunction& tf,
                       const Camera& camera) {
  detail::check_render_inputs("render_reference", mesh, scalars, tf);
  std::vector<Bounds> boxes(mesh.tets.size());
  for (std::size_t t = 0; t < boxes.size(); ++t)
    for (int k = 0; k < 4; ++k) boxes[t].extend(mesh.points[static_cast<std::size_t>(mesh.tets[t][k])]);
  const detail::Bvh bvh(boxes, 1e-9 * std::max(mesh.bounds.diagonal(), 1e-300), 4);
  const std::vector<double> breaks = tf.breakpoints();
  Image image(camera.width, camera.height);
  parallel_for(static_cast<std::size_t>(camera.height), 1, [&](std::size_t y0, std::size_t y1) {
    std::vector<Interval> iv;
    for (std::size_t y = y0; y < y1; ++y)
      for (int x = 0; x < camera.width; ++x) {
        const RefRay r(camera.primary_ray(x, static_cast<double>(y)));
        iv.clear();
        bvh.for_each_on_line(r.o, r.d, 0.0, std::numeric_limits<double>::infinity(), [&](std::int32_t t) {
          Interval i{};
          if (clip(mesh, t, r, i)) iv.push_back(i);
        });
        const RayTrace tr = integrate_intervals(mesh, scalars, tf, breaks, r, iv);
        float* px = image.pixel(x, static_cast<int>(y));
        for (int c = 0; c < 4; ++c) px[c] = static_cast<float>(tr.rgba[c]);
      }
  });
  return image;
}

}  // namespace penumbra::render

// SPDX-License-Identifier: BSD-3-Clause
// tests/unit/lighting/light_split_test.cpp -- one light volume per part of a split mesh, as ranks
// solve it: level 0 over the whole bounds merged by combine_level0, shared points settled by
// rays_enter_mesh, against the volume of the whole mesh
#include <gtest/gtest.h>

#include <cmath>

#include "lighting_test_util.h"
#include "penumbra/core/error.h"

namespace penumbra::lighting_test {
namespace {

constexpr int kCells = 12;

// A unit cube of tets; every part keeps the cube's grid points, so point ids agree across parts.
std::shared_ptr<const TetMesh> part(const fixtures::CellFilter& keep) {
  return tet_block(kCells, kCells, kCells, {0, 0, 0}, {1, 1, 1}, keep);
}

// Dense blob in the middle: the cells towards the light shadow those behind.
double blob(const Vec3d& p) {
  const Vec3d d = p - Vec3d{0.45, 0.5, 0.55};
  return std::exp(-dot(d, d) / 0.05);
}

struct Split {
  std::vector<std::shared_ptr<const TetMesh>> parts;
  std::vector<std::unique_ptr<LightVolume>> volumes;
};

LightVolumeOptions options(const Bounds& level0_bounds) {
  LightVolumeOptions o;
  o.level0_resolution = 24;
  o.level0_bounds = level0_bounds;
  return o;
}

// Each part's volume solved with level 0 merged over the parts (the maximum, as ranks reduce it).
void solve(Split& s, const Light& light, const Bounds& whole, bool merge) {
  const TransferFunction tf = ramp_tf(6.0);
  for (const auto& m : s.parts) {
    s.volumes.push_back(std::make_unique<LightVolume>(m, options(merge ? whole : Bounds{})));
    s.volumes.back()->set_field(field(*m, blob), tf);
    s.volumes.back()->set_lights({light});
  }
  if (merge) {
    std::vector<float> tau;
    std::vector<render::Level0Mask> mask;
    for (auto& v : s.volumes)  // gather
      v->combine_level0([&](std::vector<float>& t, std::vector<render::Level0Mask>& m) {
        if (tau.empty()) {
          tau = t;
          mask = m;
        }
        for (std::size_t i = 0; i < t.size(); ++i) {
          tau[i] = std::max(tau[i], t[i]);
          mask[i] = std::max(mask[i], m[i]);
        }
      });
    for (auto& v : s.volumes)  // scatter
      v->combine_level0([&](std::vector<float>& t, std::vector<render::Level0Mask>& m) {
        t = tau;
        m = mask;
      });
  }
  for (auto& v : s.volumes) ASSERT_TRUE(v->update().converged);
}

// Per point, the parts' values settled as the ranks settle them: the mean over the parts whose
// cells the ray towards the light enters, or over all parts using the point when none does.
std::vector<double> settled(const Split& s, const Light& light, std::size_t points) {
  std::vector<double> sum(points, 0), best(points, -1), count(points, 0);
  for (std::size_t i = 0; i < s.parts.size(); ++i) {
    const auto used = used_points(*s.parts[i]);
    std::vector<std::int32_t> ids;
    for (std::size_t p = 0; p < points; ++p)
      if (used[p]) ids.push_back(static_cast<std::int32_t>(p));
    const auto enters = render::rays_enter_mesh(*s.parts[i], ids, light);
    const auto& rho = s.volumes[i]->light_rho(0);
    for (std::size_t j = 0; j < ids.size(); ++j) {
      const auto p = static_cast<std::size_t>(ids[j]);
      if (enters[j] > best[p]) {
        best[p] = enters[j];
        sum[p] = count[p] = 0;
      }
      if (enters[j] == best[p]) {
        sum[p] += rho[p];
        count[p] += 1;
      }
    }
  }
  for (std::size_t p = 0; p < points; ++p) sum[p] /= count[p];
  return sum;
}

struct Difference {
  double rms = 0, max = 0;
};
Difference difference(const std::vector<double>& parts, const std::vector<float>& whole) {
  Difference d;
  for (std::size_t p = 0; p < whole.size(); ++p) {
    const double e = std::fabs(parts[p] - whole[p]);
    d.rms += e * e;
    d.max = std::max(d.max, e);
  }
  d.rms = std::sqrt(d.rms / static_cast<double>(whole.size()));
  return d;
}

Difference split_vs_whole(const fixtures::CellFilter& first_part, const Light& light, bool merge) {
  const auto whole = part({});
  LightVolume lv(whole, options({}));
  lv.set_field(field(*whole, blob), ramp_tf(6.0));
  lv.set_lights({light});
  EXPECT_TRUE(lv.update().converged);
  Split s;
  s.parts = {part(first_part), part([&](int i, int j, int k) { return !first_part(i, j, k); })};
  solve(s, light, whole->bounds, merge);
  return difference(settled(s, light, whole->points.size()), lv.light_rho(0));
}

// The yardstick: level 0 alone against the two-level solve, the error that a walk continuing in
// level 0 at a part's edge falls back to.
Difference level0_vs_whole(const Light& light) {
  const auto whole = part({});
  LightVolumeOptions o = options({});
  o.mode = render::LightSolveMode::level0_only;
  LightVolume lv(whole, options({})), l0(whole, o);
  for (LightVolume* v : {&lv, &l0}) {
    v->set_field(field(*whole, blob), ramp_tf(6.0));
    v->set_lights({light});
    EXPECT_TRUE(v->update().converged);
  }
  const auto& rho0 = l0.light_rho(0);
  return difference(std::vector<double>(rho0.begin(), rho0.end()), lv.light_rho(0));
}

const fixtures::CellFilter kSlabs = [](int i, int, int) { return i < kCells / 2; };
// Cells dealt alternately (a checkerboard of cubes): every walk leaves its part after one cube.
const fixtures::CellFilter kInterleaved = [](int i, int j, int k) { return (i + j + k) % 2 == 0; };

// The light crosses the cut between the slabs: without the merged level 0 the far slab loses the
// near slab's shadow; with it, only the walks that reach the cut fall back to level 0.
TEST(LightSplit, SlabsWithMergedLevel0StayWellWithinTheLevel0Error) {
  for (const Light& light : {directional({1, 0.3, -0.4}), point_light({1.6, 0.5, 0.6})}) {
    const Difference level0 = level0_vs_whole(light);
    const Difference merged = split_vs_whole(kSlabs, light, true);
    const Difference alone = split_vs_whole(kSlabs, light, false);
    EXPECT_LT(merged.rms, 0.6 * level0.rms);
    EXPECT_LT(merged.max, 0.6 * level0.max);
    EXPECT_GT(alone.max, 0.2);  // what the merge buys: the other part's shadow
  }
}

// Every walk leaves its part within a cube and continues in level 0: the result lies between
// the two-level solve and level 0 alone.
TEST(LightSplit, InterleavedPartsStayWithinTheLevel0Error) {
  for (const Light& light : {directional({1, 0.3, -0.4}), point_light({1.6, 0.5, 0.6})}) {
    const Difference level0 = level0_vs_whole(light);
    const Difference merged = split_vs_whole(kInterleaved, light, true);
    EXPECT_LT(merged.rms, level0.rms);
    EXPECT_LT(merged.max, level0.max);
  }
}

TEST(LightSplit, RaysEnterMeshAtBoundaryAndInteriorPoints) {
  const auto slab = part(kSlabs);  // x in [0, 0.5]
  // Corner (0,0,0) is point 0, the cut's middle point (0.5, 0.5, 0.5) is interior to the cube.
  const std::int32_t n = kCells + 1;
  const std::int32_t middle = kCells / 2 + n * (kCells / 2 + n * (kCells / 2));
  const auto towards_plus_x = render::rays_enter_mesh(*slab, {0, middle}, directional({-1, 0, 0}));
  const auto towards_minus_x = render::rays_enter_mesh(*slab, {0, middle}, directional({1, 0, 0}));
  EXPECT_EQ(towards_plus_x, (std::vector<std::uint8_t>{1, 0}));   // from the cut into the other slab
  EXPECT_EQ(towards_minus_x, (std::vector<std::uint8_t>{0, 1}));  // back into this slab
  EXPECT_THROW(render::rays_enter_mesh(*slab, {-1}, directional({1, 0, 0})), Error);
}

TEST(LightSplit, CombineLevel0RejectsResizingAndNeedsAField) {
  const auto m = part(kSlabs);
  LightVolume lv(m, options(Bounds{}));
  EXPECT_THROW(lv.combine_level0([](std::vector<float>&, std::vector<render::Level0Mask>&) {}), Error);
  lv.set_field(field(*m, blob), ramp_tf(1.0));
  EXPECT_THROW(lv.combine_level0([](std::vector<float>& t, std::vector<render::Level0Mask>&) { t.pop_back(); }), Error);
  EXPECT_THROW(lv.combine_level0({}), Error);
  LightVolumeOptions bad = options(Bounds{});
  bad.level0_bounds.lo = {0, 0, 0};
  bad.level0_bounds.hi = {1, NAN, 1};
  EXPECT_THROW(LightVolume(m, bad), Error);
}

}  // namespace
}  // namespace penumbra::lighting_test

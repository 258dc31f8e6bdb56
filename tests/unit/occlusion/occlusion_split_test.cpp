// SPDX-License-Identifier: BSD-3-Clause
// tests/unit/occlusion/occlusion_split_test.cpp -- cone-traced occlusion of a mesh split into parts,
// as ranks compute it (OcclusionLighting's halves: extinction grids merged, shadow gaps integrated
// through every part), against the whole mesh
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>

#include "fixtures/meshes.h"
#include "penumbra/core/error.h"
#include "penumbra/render/occlusion.h"
#include "penumbra/render/tet_mesh.h"

namespace penumbra {
namespace {

constexpr int kCells = 10;

std::shared_ptr<const render::TetMesh> part(const fixtures::CellFilter& keep) {
  return std::make_shared<const render::TetMesh>(
      render::prepare_tet_mesh(fixtures::block(fixtures::BlockCells::tets, kCells, kCells, kCells, {0, 0, 0}, {1, 1, 1}, keep).view()));
}

std::vector<float> blob(const render::TetMesh& m) {
  std::vector<float> s(m.points.size());
  for (std::size_t p = 0; p < s.size(); ++p) {
    const Vec3d d = m.points[p] - Vec3d{0.45, 0.5, 0.55};
    s[p] = static_cast<float>(std::exp(-dot(d, d) / 0.05));
  }
  return s;
}

render::TransferFunction ramp() {
  render::TransferFunction tf;
  tf.colors = {{0, 1, 1, 1}};
  tf.opacities = {{0, 0}, {1, 8}};
  return tf;
}

render::OcclusionSettings settings(const Bounds& grid_bounds) {
  render::OcclusionSettings s;
  s.grid_resolution = 24;
  s.grid_bounds = grid_bounds;
  return s;
}

const std::vector<render::Light> kLights = {{render::Light::Kind::directional, {1, 0.3, -0.4}, {1, 1, 1}},
                                             {render::Light::Kind::point, {1.6, 0.5, 0.6}, {0.5, 0.4, 0.3}}};
const Vec3d kEye{2.5, -1.5, 2.0};

// Largest |parts - whole| of the light per point, over every point some part uses.
double split_vs_whole(const fixtures::CellFilter& first, bool exchange_gaps) {
  const auto whole = part({});
  render::OcclusionLighting all(whole, settings({}), kLights);
  all.set_field(blob(*whole), ramp());
  const std::vector<float> expected = all.light_rgb(kEye);

  const std::vector<std::shared_ptr<const render::TetMesh>> parts = {part(first), part([&](int i, int j, int k) { return !first(i, j, k); })};
  std::vector<std::unique_ptr<render::OcclusionLighting>> occ;
  std::vector<float> merged;
  for (const auto& m : parts) {
    occ.push_back(std::make_unique<render::OcclusionLighting>(m, settings(whole->bounds), kLights));
    occ.back()->resample_field(blob(*m), ramp());
    occ.back()->combine_extinction([&](std::vector<float>& tau) {
      if (merged.empty()) merged.assign(tau.size(), 0.0f);
      for (std::size_t i = 0; i < tau.size(); ++i) merged[i] = std::max(merged[i], tau[i]);
    });
  }
  for (auto& o : occ) o->combine_extinction([&](std::vector<float>& tau) { tau = merged; });
  for (std::size_t i = 0; i < occ.size(); ++i) {
    const std::vector<render::GapSegment> open = occ[i]->open_gaps();
    std::vector<double> extra(open.size(), 0.0);
    if (exchange_gaps) extra = occ[1 - i]->gap_depths(open);
    occ[i]->add_gap_depths(extra);
  }
  double worst = 0;
  for (std::size_t i = 0; i < occ.size(); ++i) {
    occ[i]->finish_field();
    const std::vector<float>& got = occ[i]->light_rgb(kEye);
    std::vector<bool> used(parts[i]->points.size(), false);
    for (const auto& t : parts[i]->tets)
      for (auto v : t) used[static_cast<std::size_t>(v)] = true;
    for (std::size_t p = 0; p < used.size(); ++p)
      for (int c = 0; used[p] && c < 3; ++c)
        worst = std::max(worst, std::fabs(double(got[3 * p + c]) - expected[3 * p + c]));
  }
  return worst;
}

const fixtures::CellFilter kSlabs = [](int i, int, int) { return i < kCells / 2; };
const fixtures::CellFilter kInterleaved = [](int i, int j, int k) { return (i + j + k) % 2 == 0; };

// The merged grid is the whole mesh's and the gaps add up over disjoint cells: the parts' light
// is the whole mesh's to float rounding. Without the gaps' exchange the shadows lose the other
// part's medium next to the points (the check can fail).
TEST(OcclusionSplit, PartsGiveTheWholeMeshLight) {
  for (const auto& split : {kSlabs, kInterleaved}) {
    EXPECT_LT(split_vs_whole(split, true), 1e-5);
    EXPECT_GT(split_vs_whole(split, false), 1e-2);
  }
}

TEST(OcclusionSplit, HalvesAreCalledInOrderAndKeepTheirSizes) {
  const auto m = part(kSlabs);
  render::OcclusionLighting occ(m, settings({}), kLights);
  EXPECT_THROW(occ.combine_extinction([](std::vector<float>&) {}), Error);
  EXPECT_THROW(occ.open_gaps(), Error);
  EXPECT_THROW(occ.finish_field(), Error);
  occ.resample_field(blob(*m), ramp());
  EXPECT_THROW(occ.combine_extinction({}), Error);
  const auto open = occ.open_gaps();
  EXPECT_FALSE(open.empty());  // the cut and the block's faces
  EXPECT_THROW(occ.add_gap_depths(std::vector<double>(open.size() + 1, 0.0)), Error);
  occ.resample_field(blob(*m), ramp());
  EXPECT_THROW(occ.combine_extinction([](std::vector<float>& tau) { tau.pop_back(); }), Error);
}

}  // namespace
}  // namespace penumbra

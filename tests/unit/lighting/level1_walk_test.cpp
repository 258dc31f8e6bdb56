// SPDX-License-Identifier: BSD-3-Clause
// tests/unit/lighting/level1_walk_test.cpp -- the level-1 walk towards the light
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <vector>

#include "lighting/level1_mesh.h"
#include "lighting/level1_walk.h"
#include "lighting_test_util.h"

namespace penumbra::lighting_test {
namespace {

using render::lighting::ParallelPoint;
using render::lighting::Trace;
using render::lighting::WalkInput;
using render::lighting::WalkJob;
using render::lighting::WalkCrossing;

// A mesh with its walk inputs for one field and transfer function.
struct WalkScene {
  std::shared_ptr<const TetMesh> mesh;
  render::lighting::Level1Topology topology;
  render::lighting::Level1Field field;
  std::vector<ParallelPoint> parallel;

  WalkScene(std::shared_ptr<const TetMesh> m, const std::vector<float>& s, const TransferFunction& tf)
      : mesh(std::move(m)), topology(*mesh) {
    field.build(s, tf);
  }
  // Inputs for a directional light towards `towards` (unit), or for a point light (null).
  WalkInput input(const Vec3d* towards) {
    if (towards) render::lighting::project_parallel(*mesh, *towards, field.scalars, parallel);
    return {topology.walk_tets, topology.tet_offsets, topology.star, field.table,
            towards ? parallel.data() : nullptr, mesh->points.data(), field.scalars.data()};
  }
};

bool same(const Trace& a, const Trace& b) {
  return a.kind == b.kind && a.tet == b.tet && a.end == b.end && a.depth == b.depth &&
         std::memcmp(a.weights, b.weights, sizeof a.weights) == 0;
}

// walk_batch (several walks in flight) gives every walk exactly what walk_to_light gives, its
// segments and start cache included: directional and point light, on a mesh with a hole (walks
// that leave and re-enter the mesh) and an axis-aligned light (rays along faces and edges,
// starts retried on turned planes).
TEST(Level1Walk, BatchEqualsSingleWalks) {
  const auto mesh = prepare(fixtures::tet_block_with_hole(9));
  WalkScene sc(mesh, field(*mesh, [](const Vec3d& p) { return 0.3 + 0.6 * p.x * p.y + 0.2 * std::sin(5 * p.z); }),
               ramp_tf(2.0));
  const Vec3d axis{-1, 0, 0}, oblique = normalize(Vec3d{-0.8, 0.45, 0.4});
  const Vec3d light{0.5, 1.7, 0.45};
  for (int variant = 0; variant < 3; ++variant) {
    const Vec3d* towards = variant == 0 ? &axis : variant == 1 ? &oblique : nullptr;
    const WalkInput in = sc.input(towards);
    const std::size_t np = sc.mesh->points.size();
    std::vector<WalkJob> jobs;
    std::vector<std::vector<WalkCrossing>> batch_segments(np), single_segments(np);
    std::vector<std::int32_t> batch_start(np, -1), single_start(np, -1);
    std::vector<Trace> single(np);
    for (std::size_t p = 0; p < np; ++p) {
      const Vec3d& x = sc.mesh->points[p];
      const Vec3d d = towards ? *towards : normalize(light - x);
      const double len = 0.35;
      const auto v = static_cast<std::int32_t>(p);
      single[p] = render::lighting::walk_to_light(in, v, x, d, len, &single_start[p], &single_segments[p]);
      jobs.push_back({v, x, d, len, &batch_start[p], &batch_segments[p], {}});
    }
    render::lighting::walk_batch(in, jobs.data(), jobs.size());
    int inside = 0;
    for (std::size_t p = 0; p < np; ++p) {
      ASSERT_TRUE(same(jobs[p].trace, single[p])) << "variant " << variant << " point " << p;
      ASSERT_EQ(batch_start[p], single_start[p]) << "variant " << variant << " point " << p;
      ASSERT_EQ(batch_segments[p].size(), single_segments[p].size()) << "variant " << variant << " point " << p;
      for (std::size_t k = 0; k < single_segments[p].size(); ++k) {
        EXPECT_EQ(0, std::memcmp(&batch_segments[p][k], &single_segments[p][k], sizeof(WalkCrossing)));
      }
      inside += single[p].kind == Trace::Kind::inside;
    }
    EXPECT_GT(inside, static_cast<int>(np / 4)) << "variant " << variant;  // np counts the hole's unused points
  }
}

// A start found for one direction, kept as a hint (hint_start) when the light turns, gives the
// walk for the new direction exactly what a search from scratch gives, start cache included:
// where the hint is still the start (a small turn: most vertices) and where it is not (a large
// one), directional and point lights, and from an axis-aligned light (its starts were chosen by
// the tie rule, and a slight tilt moves them: no hint holds).
TEST(Level1Walk, HintedStartsEqualSearchedStarts) {
  const auto mesh = prepare(fixtures::tet_block_with_hole(9));
  WalkScene sc(mesh, field(*mesh, [](const Vec3d& p) { return 0.3 + 0.6 * p.x * p.y + 0.2 * std::sin(5 * p.z); }),
               ramp_tf(2.0));
  struct Turn {
    Vec3d from, to;  // directions (towards the light), or point lights' positions
    bool point;
    int kept_half;  // +1: most hints still hold; -1: most do not; 0: either
  };
  const std::vector<Turn> turns{
      {normalize(Vec3d{-0.8, 0.45, 0.4}), normalize(Vec3d{-0.78, 0.49, 0.39}), false, 1},
      {normalize(Vec3d{-0.8, 0.45, 0.4}), normalize(Vec3d{0.3, 0.9, -0.3}), false, -1},
      {Vec3d{-1, 0, 0}, normalize(Vec3d{-1, 0.05, 0.03}), false, 0},
      {Vec3d{0.5, 1.7, 0.45}, Vec3d{0.55, 1.68, 0.5}, true, 1},
  };
  const std::size_t np = sc.mesh->points.size();
  for (std::size_t t = 0; t < turns.size(); ++t) {
    const Turn& turn = turns[t];
    auto ray = [&](std::size_t p, const Vec3d& towards) {
      return turn.point ? normalize(towards - sc.mesh->points[p]) : towards;
    };
    std::vector<std::int32_t> hinted(np, -1), searched(np, -1);
    const WalkInput before = sc.input(turn.point ? nullptr : &turn.from);
    for (std::size_t p = 0; p < np; ++p)
      (void)render::lighting::walk_to_light(before, static_cast<std::int32_t>(p), sc.mesh->points[p], ray(p, turn.from),
                                            0.35, &hinted[p]);
    std::vector<std::int32_t> old_start = hinted;
    for (std::int32_t& start : hinted) start = render::lighting::hint_start(start);
    const WalkInput after = sc.input(turn.point ? nullptr : &turn.to);
    int kept = 0, hints = 0;
    for (std::size_t p = 0; p < np; ++p) {
      const auto v = static_cast<std::int32_t>(p);
      const Vec3d& x = sc.mesh->points[p];
      std::vector<WalkCrossing> with_hint, without;
      const Trace a = render::lighting::walk_to_light(after, v, x, ray(p, turn.to), 0.35, &hinted[p], &with_hint);
      const Trace b = render::lighting::walk_to_light(after, v, x, ray(p, turn.to), 0.35, &searched[p], &without);
      ASSERT_TRUE(same(a, b)) << "turn " << t << " point " << p;
      ASSERT_EQ(hinted[p], searched[p]) << "turn " << t << " point " << p;
      ASSERT_EQ(with_hint.size(), without.size()) << "turn " << t << " point " << p;
      for (std::size_t k = 0; k < without.size(); ++k)
        EXPECT_EQ(0, std::memcmp(&with_hint[k], &without[k], sizeof(WalkCrossing)));
      hints += old_start[p] >= 0;
      kept += old_start[p] >= 0 && old_start[p] == searched[p];
    }
    ASSERT_GT(hints, static_cast<int>(np / 4)) << "turn " << t;
    if (turn.kept_half > 0) EXPECT_GT(kept, hints / 2) << "turn " << t << ": most hints should still be the start";
    if (turn.kept_half < 0) EXPECT_LT(kept, hints / 2) << "turn " << t << ": most hints should be wrong";
  }
}

// The starts that one sweep over the tets hints for a new directional light
// (hint_parallel_starts) are the searched starts wherever the rays are generic, and where they
// are not (an axis-aligned light: rays along faces and edges, the tie rule decides) the walks
// are still exactly the searched ones, start cache included. Slices give what one sweep gives,
// and a cached start or -2 is never replaced.
TEST(Level1Walk, SweptHintsAreTheSearchedStarts) {
  const auto mesh = prepare(fixtures::tet_block_with_hole(9));
  WalkScene sc(mesh, field(*mesh, [](const Vec3d& p) { return 0.3 + 0.6 * p.x * p.y + 0.2 * std::sin(5 * p.z); }),
               ramp_tf(2.0));
  const std::size_t np = sc.mesh->points.size(), nt = sc.topology.walk_tets.size();
  const Vec3d oblique = normalize(Vec3d{-0.8, 0.45, 0.4}), axis{-1, 0, 0};
  for (const Vec3d* towards : {&oblique, &axis}) {
    const WalkInput in = sc.input(towards);
    std::vector<float> xy;
    render::lighting::hint_plane(sc.parallel, xy);
    std::vector<std::int32_t> swept(np, -1), sliced(np, -1), searched(np, -1);
    render::lighting::hint_parallel_starts(sc.topology.walk_tets, xy, 0, nt, swept);
    for (std::size_t first = 0; first < nt; first += 1000)
      render::lighting::hint_parallel_starts(sc.topology.walk_tets, xy, first, std::min(nt, first + 1000), sliced);
    EXPECT_EQ(swept, sliced);
    int hinted = 0, right = 0, interior = 0;
    for (std::size_t p = 0; p < np; ++p) {
      const auto v = static_cast<std::int32_t>(p);
      const Vec3d& x = sc.mesh->points[p];
      std::vector<WalkCrossing> with_hint, without;
      const std::int32_t hint = swept[p];
      const Trace a = render::lighting::walk_to_light(in, v, x, *towards, 0.35, &swept[p], &with_hint);
      const Trace b = render::lighting::walk_to_light(in, v, x, *towards, 0.35, &searched[p], &without);
      ASSERT_TRUE(same(a, b)) << "point " << p;
      ASSERT_EQ(swept[p], searched[p]) << "point " << p;
      ASSERT_EQ(with_hint.size(), without.size()) << "point " << p;
      for (std::size_t k = 0; k < without.size(); ++k)
        EXPECT_EQ(0, std::memcmp(&with_hint[k], &without[k], sizeof(WalkCrossing)));
      hinted += hint != -1;
      right += hint != -1 && render::lighting::kFirstHint - hint == searched[p];
      interior += searched[p] >= 0;
    }
    if (towards == &oblique) {
      // Generic rays: every vertex that starts inside got its start from the sweep.
      EXPECT_EQ(right, hinted);
      EXPECT_EQ(hinted, interior);
      EXPECT_GT(interior, static_cast<int>(np / 2));
    }
    // A cached start and a ray leaving at its vertex (-2) stay; unknown and hinted entries are
    // replaced.
    std::vector<std::int32_t> kept(np, -1);
    for (std::size_t p = 0; p < np; ++p) kept[p] = p % 4 == 0 ? 7 : p % 4 == 1 ? -2 : p % 4 == 2 ? render::lighting::kFirstHint - 5 : -1;
    render::lighting::hint_parallel_starts(sc.topology.walk_tets, xy, 0, nt, kept);
    for (std::size_t p = 0; p < np; ++p) {
      if (p % 4 == 0) EXPECT_EQ(kept[p], 7);
      if (p % 4 == 1) EXPECT_EQ(kept[p], -2);
      if (p % 4 >= 2 && swept[p] >= 0 && towards == &oblique) EXPECT_EQ(render::lighting::kFirstHint - kept[p], swept[p]);
    }
  }
}

// In a homogeneous medium the optical depth of a walk is tau times the length it ran inside the
// mesh, whatever the direction: along grid edges and faces (where every exit is a tie), obliquely,
// and from boundary vertices along the boundary (which the tie rule alone would push outside:
// the turned retries start those walks inside). The departure weights reproduce the end point.
TEST(Level1Walk, HomogeneousDepthAlongTiesAndBoundaries) {
  const auto mesh = tet_block(6, 6, 6, {0, 0, 0}, {1, 1, 1});
  const double tau = 1.7;
  WalkScene sc(mesh, field(*mesh, [](const Vec3d&) { return 0.0; }), constant_tf(tau));
  for (const Vec3d dir : {Vec3d{-1, 0, 0}, Vec3d{0, 0, -1}, normalize(Vec3d{-1, -1, 0}), normalize(Vec3d{-0.7, -0.2, -0.4})}) {
    const WalkInput in = sc.input(&dir);
    int along_boundary = 0;
    for (std::size_t p = 0; p < mesh->points.size(); ++p) {
      const Vec3d& x = mesh->points[p];
      const double len = 0.5;
      const Trace tr = render::lighting::walk_to_light(in, static_cast<std::int32_t>(p), x, dir, len);
      // Where the ray leaves the unit cube (closed): the walk must run exactly that far.
      double inside = HUGE_VAL;
      for (int a = 0; a < 3; ++a) {
        if (dir[a] < 0) inside = std::min(inside, -x[a] / dir[a]);
        if (dir[a] > 0) inside = std::min(inside, (1 - x[a]) / dir[a]);
      }
      const double expect = std::min(len, inside);
      ASSERT_NEAR(tr.end, expect, 1e-12) << "point " << p << " dir " << dir.x << " " << dir.y << " " << dir.z;
      ASSERT_NEAR(tr.depth, tau * expect, 1e-12) << "point " << p;
      if (expect < len) {
        EXPECT_EQ(tr.kind, Trace::Kind::left_mesh) << "point " << p;
        continue;
      }
      ASSERT_EQ(tr.kind, Trace::Kind::inside) << "point " << p;
      // On a face of the cube with the ray in that face: inside only thanks to the retries.
      for (int a = 0; a < 3; ++a)
        if (dir[a] == 0 && (x[a] == 0 || x[a] == 1)) ++along_boundary;
      Vec3d at{0, 0, 0};
      const auto& tv = sc.topology.walk_tets[static_cast<std::size_t>(tr.tet)].v;
      for (int k = 0; k < 4; ++k) at = at + mesh->points[static_cast<std::size_t>(tv[k])] * static_cast<double>(tr.weights[k]);
      const Vec3d want = x + dir * len;
      EXPECT_NEAR(length(at - want), 0.0, 1e-6) << "point " << p;
    }
    if (dir.y == 0 && dir.z == 0) EXPECT_GT(along_boundary, 50);
  }
}

}  // namespace
}  // namespace penumbra::lighting_test

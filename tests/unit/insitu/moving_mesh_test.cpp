// SPDX-License-Identifier: BSD-3-Clause
// tests/unit/insitu/moving_mesh_test.cpp -- a mesh whose points move under one topology_version:
// the pictures of a mesh prepared anew, on every backend and lighting model, and named errors
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <string>

#include "cinema_database.h"
#include "config.h"
#include "context.h"
#include "fixtures/meshes.h"
#include "penumbra/core/error.h"
#include "penumbra/render/gpu_ray_caster.h"
#include "penumbra/render/image.h"
#include "test_util.h"

namespace penumbra::insitu {
namespace {

using fixtures::BlockCells;
using testing::TempDir;

struct MovingScene {
  fixtures::OwnedMesh before = fixtures::block(BlockCells::hexes, 6, 6, 5, {0, 0, 0}, {1, 1, 1});
  fixtures::OwnedMesh after = before;
  std::vector<double> field = fixtures::sample(before, [](double x, double y, double z) {
    return std::exp(-6 * ((x - .4) * (x - .4) + (y - .5) * (y - .5) + (z - .6) * (z - .6)));
  });
  MovingScene() { fixtures::swirl(after, {0.5, 0.5, 0}, 0.6, 0.35); }
};

std::string config(const std::string& dir, const std::string& extra) {
  return testing::small_config(dir, R"([{"name": "T"}])", extra);
}

std::vector<std::vector<std::string>> rows(const std::string& dir) {
  return CinemaDatabase::parse_csv(testing::read_text(dir + "/data.csv"), "data.csv");
}

std::vector<unsigned char> image_of(const std::string& dir, std::size_t row) {
  int w = 0, h = 0;
  return render::read_png_rgb(dir + "/" + rows(dir)[row].back(), w, h);
}

struct Difference {
  int max_levels = 0;
  double rms_pct = 0;
};
Difference difference(const std::vector<unsigned char>& a, const std::vector<unsigned char>& b) {
  Difference d;
  double sum = 0;
  for (std::size_t i = 0; i < a.size() && i < b.size(); ++i) {
    const int e = std::abs(int(a[i]) - int(b[i]));
    d.max_levels = std::max(d.max_levels, e);
    sum += double(e) * e;
  }
  d.rms_pct = a.empty() ? 0 : 100 * std::sqrt(sum / double(a.size())) / 255;
  return d;
}

// Renders the scene's moved step twice: in a run whose mesh moved under its topology_version
// since the step before, and in a run that publishes the moved mesh as its first topology.
// Returns the two pictures of the moved step (the first camera) and checks the first run's counts.
std::pair<std::vector<unsigned char>, std::vector<unsigned char>> moved_and_fresh(const std::string& extra) {
  TempDir tmp;
  MovingScene s;
  const std::string moving = tmp / "moving", fresh = tmp / "fresh";
  {
    Context ctx(parse_config(config(moving, extra)));
    ctx.publish_mesh(s.before.view());
    ctx.publish_field(fixtures::point_field("T", s.field), false);
    EXPECT_TRUE(ctx.execute(0.0, 0));
    ctx.publish_mesh(s.after.view());
    ctx.publish_field(fixtures::point_field("T", s.field), false);
    EXPECT_TRUE(ctx.execute(1.0, 1));
    EXPECT_EQ(ctx.mesh_preparations(), 1u);
    EXPECT_EQ(ctx.geometry_updates(), 1u);
  }
  {
    Context ctx(parse_config(config(fresh, extra)));
    ctx.publish_mesh(s.after.view());
    ctx.publish_field(fixtures::point_field("T", s.field), false);
    EXPECT_TRUE(ctx.execute(1.0, 1));
  }
  return {image_of(moving, 3), image_of(fresh, 1)};
}

bool gpu_runs() {
  if (!render::gpu_backend_compiled()) return false;
  try {
    render::GpuOptions quiet;
    quiet.log = [](const std::string&) {};
    render::GpuDevice::open(quiet);
    return true;
  } catch (const Error&) {
    return false;
  }
}

const char* const kPhong = R"(, "lighting": {"model": "phong"})";
const char* const kOcclusion =
    R"(, "lighting": {"model": "occlusion", "lights": [{"type": "directional", "direction": [-1, -0.5, -1]}],
        "occlusion": {"shadows": true}})";
const char* const kLightVolume =
    R"(, "lighting": {"model": "light-volume", "level0_resolution": 16, "absorption": 2,
        "lights": [{"type": "directional", "direction": [-1, -0.5, -1]}]})";

// Occlusion is made again for the moved mesh, so its pictures are those of a new topology too.
TEST(MovingMesh, UnlitPhongAndOcclusionPicturesAreThoseOfTheMeshPreparedAnew) {
  for (const std::string backend : {"cpu", "gpu"}) {
    if (backend == "gpu" && !gpu_runs()) continue;
    for (const std::string lighting : {std::string(), std::string(kPhong), std::string(kOcclusion)}) {
      const auto [moved, fresh] = moved_and_fresh(R"(, "backend": ")" + backend + "\"" + lighting);
      EXPECT_EQ(moved, fresh) << backend << lighting;
    }
  }
}

// The light volume of the moved mesh continues from the light before the motion; converged, it is
// the light of a volume made for the moved mesh within the solve's own tolerance (a pass stops
// when no vertex changes by more than 1/40 of a level: the two solves end within a level).
TEST(MovingMesh, TheConvergedLightIsThatOfAVolumeMadeForTheMovedMesh) {
  for (const std::string backend : {"cpu", "gpu"}) {
    if (backend == "gpu" && !gpu_runs()) continue;
    const auto [moved, fresh] = moved_and_fresh(R"(, "backend": ")" + backend + "\"" + kLightVolume);
    const Difference d = difference(moved, fresh);
    EXPECT_LE(d.max_levels, 1) << backend;
    EXPECT_LE(d.rms_pct, 0.2) << backend;
  }
}

TEST(MovingMesh, MotionThatInvertsACellIsANamedErrorAndTheRunGoesOn) {
  TempDir tmp;
  MovingScene s;
  Context ctx(parse_config(config(tmp / "db", "")));
  ctx.publish_mesh(s.before.view());
  auto crushed = s.before;
  const std::size_t p = 3 + 7 * (3 + 7 * 2);  // an interior point pushed through its neighbours
  crushed.xyz[3 * p + 2] += 0.5;
  try {
    ctx.publish_mesh(crushed.view());
    ADD_FAILURE() << "expected the inverted cell to be refused";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::invalid_argument);
    const std::string text = e.what();
    EXPECT_NE(text.find("pnb_publish_mesh: cell "), std::string::npos) << text;
    EXPECT_NE(text.find("by the points' motion"), std::string::npos) << text;
  }
  // The mesh before the motion is still held: its step renders, and a valid motion is taken.
  ctx.publish_field(fixtures::point_field("T", s.field), false);
  EXPECT_TRUE(ctx.execute(0.0, 0));
  ctx.publish_mesh(s.after.view());
  EXPECT_EQ(ctx.geometry_updates(), 1u);
  EXPECT_EQ(ctx.mesh_preparations(), 1u);
}

TEST(MovingMesh, RepublishingUnmovedPointsCostsNoUpdate) {
  TempDir tmp;
  MovingScene s;
  Context ctx(parse_config(config(tmp / "db", "")));
  ctx.publish_mesh(s.before.view());
  ctx.publish_mesh(s.before.view());
  EXPECT_EQ(ctx.geometry_updates(), 0u);
  auto nudged = s.before;
  nudged.xyz[3 * 17 + 1] += 1e-9;  // one coordinate, one part in a billion: noticed
  ctx.publish_mesh(nudged.view());
  EXPECT_EQ(ctx.geometry_updates(), 1u);
  EXPECT_EQ(ctx.mesh_preparations(), 1u);
}

}  // namespace
}  // namespace penumbra::insitu

// SPDX-License-Identifier: BSD-3-Clause
// tests/unit/insitu/lighting_config_test.cpp -- the "lighting" config object, and lit steps
#include <gtest/gtest.h>

#include <cmath>
#include <map>

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

std::string with_lighting(const std::string& dir, const std::string& lighting, const std::string& extra = "") {
  return testing::small_config(dir, R"([{"name": "T"}])", R"(, "lighting": )" + lighting + extra);
}

void expect_config_error(const std::string& lighting, const std::string& needle) {
  try {
    parse_config(with_lighting("/tmp/unused", lighting));
    ADD_FAILURE() << "expected an error containing: " << needle;
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::invalid_argument);
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
  }
}

TEST(LightingConfig, IsReadWithDefaults) {
  const Config plain = parse_config(testing::small_config("/tmp/unused"));
  EXPECT_FALSE(plain.lighting.has_value());
  const Config c = parse_config(with_lighting("/tmp/unused", R"({"model": "light-volume",
      "lights": [{"type": "directional", "direction": [0, 0, -2], "color": [1, 0.9, 0.8]},
                 {"type": "point", "position": [0.5, 0.5, 3]}],
      "absorption": 2.5, "scattering": [0.1, 0.2, 0.3], "level0_resolution": 32,
      "phong": {"ambient": 0.2, "specular": 0}, "budget": {"iterations": 12, "ms": 40}})"));
  ASSERT_TRUE(c.lighting.has_value());
  const LightingConfig& l = *c.lighting;
  EXPECT_EQ(l.model, render::LightingModel::light_volume);
  ASSERT_EQ(l.lights.size(), 2u);
  EXPECT_EQ(l.lights[0].kind, render::Light::Kind::directional);
  EXPECT_EQ(l.lights[0].vector.z, -2);
  EXPECT_EQ(l.lights[0].color[2], 0.8);
  EXPECT_EQ(l.lights[1].kind, render::Light::Kind::point);
  EXPECT_EQ(l.lights[1].color[0], 1.0);  // default white
  EXPECT_EQ(l.absorption, 2.5);
  EXPECT_EQ(l.scattering[1], 0.2);
  EXPECT_EQ(l.level0_resolution, 32);
  EXPECT_EQ(l.ambient, 0.2);
  EXPECT_EQ(l.diffuse, 0.55);  // default kept
  EXPECT_EQ(l.specular, 0.0);
  EXPECT_EQ(l.budget.max_work_units, 12);
  EXPECT_EQ(l.budget.max_ms, 40);
  const Config scalar = parse_config(with_lighting("/tmp/unused", R"({"model": "phong", "scattering": 0.5})"));
  EXPECT_EQ(scalar.lighting->scattering[2], 0.5);
  EXPECT_EQ(scalar.lighting->model, render::LightingModel::phong);
}

TEST(LightingConfig, EveryErrorNamesItsKeyPath) {
  expect_config_error(R"({"model": "raytraced"})", "lighting.model must be one of");
  expect_config_error(R"({"model": "light-volume"})", "lighting.lights needs at least one light");
  expect_config_error(R"({"lights": [{"direction": [0, 0, 1]}]})", "lighting.lights[0].type is required");
  expect_config_error(R"({"lights": [{"type": "spot", "direction": [0, 0, 1]}]})", "lighting.lights[0].type must be one of");
  expect_config_error(R"({"lights": [{"type": "directional"}]})", "lighting.lights[0].direction is required");
  expect_config_error(R"({"lights": [{"type": "directional", "direction": [0, 0, 0]}]})",
                      "lighting.lights[0].direction must not be the zero vector");
  expect_config_error(R"({"lights": [{"type": "point", "position": [0, 0, 1], "direction": [0, 0, 1]}]})",
                      "lighting.lights[0].direction does not apply to a point light");
  expect_config_error(R"({"lights": [{"type": "point", "position": [0, 0, 1], "color": [1, -1, 1]}]})",
                      "lighting.lights[0].color must be [r,g,b] with components >= 0");
  expect_config_error(R"({"absorption": -1})", "lighting.absorption must be >= 0");
  expect_config_error(R"({"scattering": [1, 2]})", "lighting.scattering must be a number or [r,g,b]");
  expect_config_error(R"({"level0_resolution": 2})", "lighting.level0_resolution must be in [4, 1024]");
  expect_config_error(R"({"phong": {"gloss": 1}})", "lighting.phong.gloss is not a known key");
  expect_config_error(R"({"budget": {"ms": 0}})", "lighting.budget.ms must be > 0");
  expect_config_error(R"({"shadows": true})", "lighting.shadows is not a known key");
}

struct LitScene {
  fixtures::OwnedMesh mesh = fixtures::block(BlockCells::tets, 5, 5, 5, {0, 0, 0}, {1, 1, 1});
  std::vector<double> field = fixtures::sample(mesh, [](double x, double, double) { return x; });
};

// Mean brightness of the image behind the first data row of `dir`'s database.
double mean_brightness(const std::string& dir, const std::vector<std::string>& row) {
  int w = 0, h = 0;
  const auto rgb = render::read_png_rgb(dir + "/" + row.back(), w, h);
  double sum = 0;
  for (unsigned char v : rgb) sum += v;
  return sum / static_cast<double>(rgb.size());
}

std::vector<std::vector<std::string>> run_step(const std::string& dir, const std::string& lighting) {
  LitScene s;
  // Black background, so that only the light shows.
  Context ctx(parse_config(R"({"output": {"directory": ")" + dir + R"("},
      "image": {"width": 24, "height": 20, "background": [0, 0, 0]},
      "cameras": {"phi": [-90], "theta": [20]}, "fields": [{"name": "T"}], "lighting": )" + lighting + "}"));
  ctx.publish_mesh(s.mesh.view());
  ctx.publish_field(fixtures::point_field("T", s.field), false);
  EXPECT_TRUE(ctx.execute(0.0, 1));
  return CinemaDatabase::parse_csv(testing::read_text(dir + "/data.csv"), "data.csv");
}

TEST(LightingConfig, LitStepsWriteALightingColumnAndShadowedImages) {
  TempDir tmp;
  const auto plain = run_step(tmp / "plain", R"({"model": "none"})");
  const auto lit = run_step(tmp / "lit", R"({"model": "light-volume", "absorption": 4,
      "lights": [{"type": "directional", "direction": [1, 0, 0]}], "phong": {"ambient": 1, "diffuse": 0, "specular": 0},
      "level0_resolution": 16})");
  ASSERT_EQ(plain.size(), 2u);
  ASSERT_EQ(lit.size(), 2u);
  EXPECT_EQ(plain[0], (std::vector<std::string>{"time", "phi", "theta", "field", "lighting", "FILE"}));
  EXPECT_EQ(plain[1][4], "none");
  EXPECT_EQ(lit[1][4], "light-volume");
  // Light entering at x = 0 through an absorbing block: everything behind the front is dimmer,
  // so the lit image is darker than the unlit one, but not black.
  const double b_plain = mean_brightness(tmp / "plain", plain[1]), b_lit = mean_brightness(tmp / "lit", lit[1]);
  EXPECT_LT(b_lit, 0.9 * b_plain);
  EXPECT_GT(b_lit, 0.05 * b_plain);
}

TEST(LightingConfig, OcclusionModelIsReadAndChecked) {
  const Config c = parse_config(with_lighting("/tmp/unused", R"({"model": "occlusion",
      "occlusion": {"aperture": 20, "splits": 7, "grid": 32, "space": "volume", "volume_resolution": 16,
                    "shadows": false, "attenuation": 0.8, "level": "thesis"}})"));
  ASSERT_TRUE(c.lighting->occlusion_model);
  const OcclusionConfig& o = c.lighting->occlusion;
  EXPECT_EQ(o.aperture_deg, 20);
  EXPECT_EQ(o.splits, 7);
  EXPECT_EQ(o.grid_resolution, 32);
  EXPECT_EQ(o.space, OcclusionSpace::volume);
  EXPECT_EQ(o.volume_resolution, 16);
  EXPECT_FALSE(o.shadows);
  EXPECT_EQ(o.attenuation, 0.8);
  EXPECT_EQ(o.level, render::LevelSelection::thesis);
  EXPECT_EQ(parse_config(with_lighting("/tmp/unused", R"({"model": "occlusion"})")).lighting->occlusion.level,
            render::LevelSelection::continuous);
  expect_config_error(R"({"model": "occlusion", "occlusion": {"level": "nearest"}})", "lighting.occlusion.level must be one of");
  expect_config_error(R"({"model": "occlusion", "occlusion": {"splits": 5}})", "lighting.occlusion.splits must be 1, 3 or 7");
  expect_config_error(R"({"model": "occlusion", "occlusion": {"aperture": 90}})", "lighting.occlusion.aperture must be in (0, 90)");
  expect_config_error(R"({"model": "occlusion", "occlusion": {"space": "sky"}})", "lighting.occlusion.space must be one of");
  expect_config_error(R"({"model": "occlusion", "occlusion": {"shadows": 1}})", "lighting.occlusion.shadows must be true or false");
}

TEST(LightingConfig, OcclusionStepsAreDarkerWhereTheVolumeHidesTheViewer) {
  TempDir tmp;
  const auto plain = run_step(tmp / "plain", R"({"model": "none"})");
  std::map<std::string, double> brightness;
  for (const char* space : {"points", "volume", "image"}) {
    const std::string dir = tmp / (std::string("occ-") + space);
    const auto occ = run_step(dir, std::string(R"({"model": "occlusion", "phong": {"ambient": 1, "diffuse": 0, "specular": 0},
        "lights": [{"type": "directional", "direction": [1, 0, 0]}],
        "occlusion": {"grid": 16, "splits": 3, "space": ")") + space + R"(", "volume_resolution": 12}})");
    ASSERT_EQ(occ.size(), 2u) << space;
    EXPECT_EQ(occ[1][4], "occlusion");
    const double b_plain = mean_brightness(tmp / "plain", plain[1]), b_occ = mean_brightness(dir, occ[1]);
    EXPECT_LT(b_occ, 0.95 * b_plain) << space;
    EXPECT_GT(b_occ, 0.05 * b_plain) << space;
    brightness[space] = b_occ;
  }
  // The three evaluate the same cones, at points, on a grid or along the rays: the pictures differ
  // only by how the occlusion is interpolated.
  EXPECT_NEAR(brightness["image"], brightness["points"], 0.15 * brightness["points"]);
  EXPECT_NEAR(brightness["volume"], brightness["points"], 0.15 * brightness["points"]);
  try {
    Context ctx(parse_config(with_lighting(tmp / "gpu-image", R"({"model": "occlusion", "occlusion": {"space": "image"}})",
                                           R"(, "backend": "gpu")")));
    ADD_FAILURE() << "expected backend_unavailable";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::backend_unavailable);
    EXPECT_NE(std::string(e.what()).find("CPU backend only"), std::string::npos) << e.what();
  }
}

TEST(LightingConfig, TheGpuBackendShadesLikeTheCpuBackend) {
  if (!render::gpu_backend_compiled()) GTEST_SKIP() << "built without the GPU backend";
  TempDir tmp;
  const std::string lighting = R"({"model": "light-volume", "absorption": 3, "level0_resolution": 16,
      "lights": [{"type": "directional", "direction": [1, -0.5, -0.2]}]})";
  const auto cpu = run_step(tmp / "cpu", lighting);
  std::vector<std::vector<std::string>> gpu;
  {
    // run_step with "backend": "gpu" (llvmpipe here).
    LitScene s;
    Context ctx(parse_config(R"({"output": {"directory": ")" + (tmp / "gpu") + R"("},
        "image": {"width": 24, "height": 20, "background": [0, 0, 0]}, "backend": "gpu",
        "cameras": {"phi": [-90], "theta": [20]}, "fields": [{"name": "T"}], "lighting": )" + lighting + "}"));
    ctx.publish_mesh(s.mesh.view());
    ctx.publish_field(fixtures::point_field("T", s.field), false);
    EXPECT_TRUE(ctx.execute(0.0, 1));
    gpu = CinemaDatabase::parse_csv(testing::read_text(tmp / "gpu/data.csv"), "data.csv");
  }
  ASSERT_EQ(gpu.size(), 2u);
  int w = 0, h = 0;
  const auto a = render::read_png_rgb(tmp / ("cpu/" + cpu[1].back()), w, h);
  const auto b = render::read_png_rgb(tmp / ("gpu/" + gpu[1].back()), w, h);
  // Same light field, same shading, float32 on the GPU: within the GPU-vs-CPU image bound.
  EXPECT_LT(render::rms_difference_pct(a, b), 0.5);
}

}  // namespace
}  // namespace penumbra::insitu

// SPDX-License-Identifier: BSD-3-Clause
// tests/accuracy/ray_runs_test.cpp -- a render's runs inside the mesh (RenderOptions::ray_runs):
// where each stretch of a ray enters and leaves, and what it adds; composited, they give the pixel.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstring>

#include "penumbra/core/error.h"
#include "penumbra/render/gpu_ray_caster.h"
#include "penumbra/render/renderer.h"
#include "scenes.h"

namespace penumbra {
namespace {

using render::RayRun;

// The hole block: the hole spans 1/3 < x, y < 2/3 through all z.
std::shared_ptr<const render::TetMesh> hole_block() {
  static const auto mesh = test::prepare(fixtures::tet_block_with_hole(6));
  return mesh;
}

/// The process's GPU device, or null where none opens.
std::shared_ptr<render::GpuDevice> gpu_device() {
  if (!render::gpu_backend_compiled()) return nullptr;
  try {
    return render::GpuDevice::open();
  } catch (const Error&) {
    return nullptr;
  }
}

/// A smooth field in [0, 1] over the mesh, varying along x and z.
std::vector<float> wavy_field(const render::TetMesh& mesh) {
  std::vector<float> scalars(mesh.points.size());
  for (std::size_t i = 0; i < scalars.size(); ++i)
    scalars[i] = static_cast<float>(0.5 + 0.5 * std::sin(7 * mesh.points[i].x + 3 * mesh.points[i].z));
  return scalars;
}

/// Blue and thin at 0, yellow and dense at 1.
render::TransferFunction two_colour_tf() {
  render::TransferFunction tf;
  tf.colors = {{0.0, 0.1, 0.3, 0.9}, {1.0, 1.0, 0.6, 0.1}};
  tf.opacities = {{0.0, 0.5}, {1.0, 6.0}};
  return tf;
}

/// Pixel (x, y)'s runs composited front to back, in double: premultiplied RGB and alpha.
std::array<double, 4> composite(const render::RayRuns& runs, std::size_t pixel) {
  std::array<double, 4> out{0, 0, 0, 0};
  double transmittance = 1;
  for (std::uint32_t i = runs.offsets[pixel]; i < runs.offsets[pixel + 1]; ++i) {
    const RayRun& r = runs.runs[i];
    for (int c = 0; c < 3; ++c) out[c] += transmittance * r.rgba[c];
    transmittance *= 1 - r.rgba[3];
  }
  out[3] = 1 - transmittance;
  return out;
}

// The centre pixel of an odd-sized image looks exactly along the view axis: along +x through
// the hole's middle, the ray is inside on [0, 1/3] and [2/3, 1], at depths 1 + x from the eye at
// x = -1; each run of a homogeneous medium of extinction 1.5 has opacity 1 - exp(-1.5 / 3).
TEST(RayRuns, ARayAcrossTheHoleHasTwoRunsAtTheFacesDepths) {
  render::CpuRayCaster caster(hole_block());
  const auto camera = render::Camera::look_at({-1, 0.5, 0.5}, {2, 0.5, 0.5}, {0, 0, 1}, 20, 31, 31);
  const std::vector<float> scalars(hole_block()->points.size(), 0.0f);
  render::RenderOptions options;
  options.ray_runs = true;
  render::RenderOutput out;
  caster.render(scalars, test::constant_tf(1.5), camera, options, out);
  const std::size_t centre = 15 * 31 + 15;
  ASSERT_EQ(out.runs.offsets.size(), 31u * 31u + 1);
  ASSERT_EQ(out.runs.offsets[centre + 1] - out.runs.offsets[centre], 2u);
  const RayRun* r = &out.runs.runs[out.runs.offsets[centre]];
  const double depths[4] = {1.0, 4.0 / 3.0, 5.0 / 3.0, 2.0};
  const double alpha = 1 - std::exp(-0.5);
  for (int i = 0; i < 2; ++i) {
    // float32 depths: 1.2e-7 relative.
    EXPECT_NEAR(r[i].entry_depth, depths[2 * i], 3e-7) << i;
    EXPECT_NEAR(r[i].exit_depth, depths[2 * i + 1], 3e-7) << i;
    // The closed-form segment integral in double, then float32.
    EXPECT_NEAR(r[i].rgba[3], alpha, 1e-6) << i;
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(r[i].rgba[c], alpha, 1e-6) << i;  // white emission
  }
}

// Composited front to back, every pixel's runs give its pixel (to float32's rounding of each
// run), with a varying field, Phong shading, pixels that miss the mesh and rays that re-enter.
TEST(RayRuns, CompositedRunsGiveTheImage) {
  const auto mesh = hole_block();
  render::CpuRayCaster caster(mesh);
  const std::vector<float> scalars = wavy_field(*mesh);
  const render::TransferFunction tf = two_colour_tf();
  for (const bool phong : {false, true}) {
    render::RenderOptions options;
    options.ray_runs = true;
    if (phong) options.shading.model = render::LightingModel::phong;
    const auto camera = render::Camera::orbit(mesh->bounds, 30, 10, 30, 48, 40);
    render::RenderOutput out;
    caster.render(scalars, tf, camera, options, out);
    std::size_t several = 0;
    for (std::size_t p = 0; p < std::size_t(48 * 40); ++p) {
      const auto c = composite(out.runs, p);
      const float* px = &out.image.rgba[4 * p];
      for (int k = 0; k < 4; ++k) ASSERT_NEAR(c[k], px[k], 2e-6) << "pixel " << p << " channel " << k;
      several += out.runs.offsets[p + 1] - out.runs.offsets[p] > 1;
      for (std::uint32_t i = out.runs.offsets[p]; i + 1 < out.runs.offsets[p + 1]; ++i)
        ASSERT_LE(out.runs.runs[i].exit_depth, out.runs.runs[i + 1].entry_depth) << "front to back";
    }
    EXPECT_GT(several, 20u) << "the view across the hole re-enters the mesh";
  }
}

// Asking for nothing costs nothing and changes nothing: the same image, bit for bit, with or
// without runs, and no runs unless asked.
TEST(RayRuns, TheImageIsTheSameWithOrWithoutRuns) {
  const auto mesh = hole_block();
  render::CpuRayCaster caster(mesh);
  std::vector<float> scalars(mesh->points.size());
  for (std::size_t i = 0; i < scalars.size(); ++i) scalars[i] = static_cast<float>(mesh->points[i].y);
  const auto tf = test::constant_tf(2.0);
  const auto camera = render::Camera::orbit(mesh->bounds, -50, 25, 30, 40, 32);
  const render::Image plain = caster.render(scalars, tf, camera);
  render::RenderOutput without, with;
  render::RenderOptions options;
  caster.render(scalars, tf, camera, options, without);
  options.ray_runs = true;
  caster.render(scalars, tf, camera, options, with);
  EXPECT_TRUE(without.runs.empty());
  EXPECT_FALSE(with.runs.empty());
  EXPECT_EQ(0, std::memcmp(plain.rgba.data(), without.image.rgba.data(), plain.rgba.size() * 4));
  EXPECT_EQ(0, std::memcmp(plain.rgba.data(), with.image.rgba.data(), plain.rgba.size() * 4));
}

// The GPU renderer returns the same runs as the CPU's (float32 depths relative to the mesh's
// frame: 1e-5 of the depth; colours within a tenth of an 8-bit level), and its runs composite to
// its own image.
TEST(RayRuns, TheGpuRendererReturnsTheCpuRuns) {
  const std::shared_ptr<render::GpuDevice> device = gpu_device();
  if (!device) GTEST_SKIP() << "no GPU device (or built without the GPU backend)";
  const auto mesh = hole_block();
  render::GpuRayCaster gpu(device, mesh);
  render::CpuRayCaster cpu(mesh);
  const std::vector<float> scalars = wavy_field(*mesh);
  const render::TransferFunction tf = two_colour_tf();
  render::RenderOptions options;
  options.ray_runs = true;
  const auto camera = render::Camera::orbit(mesh->bounds, 30, 10, 30, 40, 32);
  render::RenderOutput g, c;
  render::Renderer& gpu_renderer = gpu;
  render::Renderer& cpu_renderer = cpu;
  gpu_renderer.render(scalars, tf, camera, options, g);
  cpu_renderer.render(scalars, tf, camera, options, c);
  ASSERT_EQ(g.runs.offsets.size(), c.runs.offsets.size());
  std::size_t compared = 0, several = 0;
  for (std::size_t p = 0; p + 1 < g.runs.offsets.size(); ++p) {
    const auto composited = composite(g.runs, p);
    for (int k = 0; k < 4; ++k) ASSERT_NEAR(composited[k], g.image.rgba[4 * p + k], 1e-5) << "pixel " << p;
    const std::uint32_t n = g.runs.offsets[p + 1] - g.runs.offsets[p];
    if (n != c.runs.offsets[p + 1] - c.runs.offsets[p]) continue;  // a graze one precision sees and the other not
    several += n > 1;
    for (std::uint32_t i = 0; i < n; ++i) {
      const RayRun& a = g.runs.runs[g.runs.offsets[p] + i];
      const RayRun& b = c.runs.runs[c.runs.offsets[p] + i];
      EXPECT_NEAR(a.entry_depth, b.entry_depth, 1e-5 * b.entry_depth) << "pixel " << p << " run " << i;
      EXPECT_NEAR(a.exit_depth, b.exit_depth, 1e-5 * b.exit_depth) << "pixel " << p << " run " << i;
      for (int k = 0; k < 4; ++k) EXPECT_NEAR(a.rgba[k], b.rgba[k], 0.1 / 255) << "pixel " << p << " run " << i;
      ++compared;
    }
  }
  EXPECT_GT(compared, 500u);
  EXPECT_GT(several, 20u);
}

// A ray through 20 separate slabs has 20 runs: the CPU returns them all; the GPU, which returns
// up to 16 per pixel, names the pixel instead of dropping any.
TEST(RayRuns, MoreRunsThanTheGpuHoldsAreRefusedWithThePixel) {
  const auto slabs = test::prepare(fixtures::block(fixtures::BlockCells::tets, 2, 2, 39, {0, 0, 0}, {1, 1, 3.9},
                                                   [](int, int, int k) { return k % 2 == 0; }));
  const auto camera = render::Camera::look_at({0.5, 0.5, -1}, {0.5, 0.5, 2}, {0, 1, 0}, 10, 9, 9);
  const std::vector<float> scalars(slabs->points.size(), 0.0f);
  render::RenderOptions options;
  options.ray_runs = true;
  render::RenderOutput out;
  render::CpuRayCaster cpu(slabs);
  options.early_termination_opacity = 1;  // every slab, however opaque the ones before
  cpu.render(scalars, test::constant_tf(0.1), camera, options, out);
  const std::size_t centre = 4 * 9 + 4;
  EXPECT_EQ(out.runs.offsets[centre + 1] - out.runs.offsets[centre], 20u);
  const std::shared_ptr<render::GpuDevice> device = gpu_device();
  if (!device) GTEST_SKIP() << "no GPU device (or built without the GPU backend)";
  render::GpuRayCaster gpu(device, slabs);
  try {
    gpu.render(scalars, test::constant_tf(0.1), camera, options, out);
    ADD_FAILURE() << "expected a refusal";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::invalid_argument);
    EXPECT_NE(std::string(e.what()).find("runs inside the mesh, more than the 16"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace penumbra

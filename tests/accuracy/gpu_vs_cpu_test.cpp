// SPDX-License-Identifier: BSD-3-Clause
// tests/accuracy/gpu_vs_cpu_test.cpp -- the GPU ray caster (llvmpipe in CI) against the CPU one
//
// Both run the same algorithm; the GPU in float32, the CPU in float64. Tolerances:
//   - RMS of the 8-bit images below 0.5 % of 255; measured at most 0.013 %.
//   - largest 8-bit channel difference at most kMaxPixelDiff: float32 depths and scalars move
//     a composite by ~1e-5, i.e. at most one 8-bit rounding step, except where a ray grazes the
//     silhouette or a hole's wall within float32 rounding, which both renderers decide by the
//     same tie rule but from differently rounded coordinates; such a ray crosses a stretch of
//     ~1e-6 of the mesh, so even there the pixel barely moves.
//   - largest float difference per channel below 2e-3 (a lost or doubled tet anywhere shows as
//     > 1e-2 on these scenes).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "penumbra/render/gpu_ray_caster.h"
#include "penumbra/render/image.h"
#include "scenes.h"

namespace penumbra {
namespace {

using fixtures::BlockCells;

constexpr int kSize = 96;
constexpr int kMaxPixelDiff = 2;         // 8-bit levels
constexpr double kMaxFloatDiff = 2e-3;   // premultiplied float channels
constexpr double kMaxRmsPct = 0.5;

render::TransferFunction multi_point_tf() {
  render::TransferFunction tf;
  tf.colors = {{-1.0, 0.1, 0.2, 0.9}, {0.0, 0.2, 0.9, 0.3}, {0.6, 1.0, 0.8, 0.1}, {1.2, 0.9, 0.1, 0.1}};
  tf.opacities = {{-0.8, 0.0}, {-0.3, 2.5}, {0.1, 0.0}, {0.2, 0.0}, {0.5, 4.0}, {1.0, 1.0}};
  return tf;
}

double smooth_field(double x, double y, double z) { return std::sin(2.1 * x + 0.3) * std::cos(1.7 * y - 0.2) + 0.4 * z * z - 0.2; }

std::shared_ptr<render::GpuDevice> device() {
  static std::shared_ptr<render::GpuDevice> d = render::GpuDevice::open();
  return d;
}

struct Comparison {
  double rms_pct = 0, max_float = 0;
  int max_8bit = 0, covered = 0;
};

Comparison compare(const render::Image& gpu, const render::Image& cpu) {
  Comparison c;
  for (std::size_t i = 0; i < cpu.rgba.size(); ++i) c.max_float = std::max(c.max_float, double(std::fabs(gpu.rgba[i] - cpu.rgba[i])));
  for (std::size_t i = 3; i < cpu.rgba.size(); i += 4) c.covered += cpu.rgba[i] > 0.05f;
  const float background[3] = {1, 1, 1};
  const auto a = render::to_rgb8(gpu, background), b = render::to_rgb8(cpu, background);
  for (std::size_t i = 0; i < a.size(); ++i) c.max_8bit = std::max(c.max_8bit, std::abs(int(a[i]) - int(b[i])));
  c.rms_pct = render::rms_difference_pct(a, b);
  return c;
}

void expect_same_pictures(const std::string& name, const fixtures::OwnedMesh& owned, const std::vector<float>& scalars,
                          const render::TransferFunction& tf, const render::Camera& cam,
                          const render::RenderOptions& opts = {}) {
  if (!render::gpu_backend_compiled()) GTEST_SKIP() << "built without the GPU backend";
  const auto mesh = test::prepare(owned);
  render::CpuRayCaster cpu(mesh);
  render::GpuRayCaster gpu(device(), mesh);
  const auto a = gpu.render(scalars, tf, cam, opts);
  const auto b = cpu.render(scalars, tf, cam, opts);
  const Comparison c = compare(a, b);
  std::printf("[gpu-vs-cpu] %s: rms %.4f %% of 255, max 8-bit diff %d, max float diff %.2e, %d covered pixels, "
              "%.1f B/tet (mesh), %.1f B/tet (all)\n",
              name.c_str(), c.rms_pct, c.max_8bit, c.max_float, c.covered, gpu.memory().mesh_bytes_per_tet(),
              gpu.memory().total_bytes_per_tet());
  EXPECT_LT(c.rms_pct, kMaxRmsPct) << name;
  EXPECT_LE(c.max_8bit, kMaxPixelDiff) << name;
  EXPECT_LT(c.max_float, kMaxFloatDiff) << name;
  EXPECT_GT(c.covered, 500) << name << ": the scene must actually show the volume";
}

std::vector<float> field_on(const fixtures::OwnedMesh& m) { return test::to_float(fixtures::sample(m, smooth_field)); }

TEST(GpuVsCpu, ConvexTetBlock) {
  const auto m = fixtures::block(BlockCells::tets, 7, 6, 5, {-1, -1, -1}, {1, 1, 1});
  const auto mesh = test::prepare(m);
  expect_same_pictures("convex tet block", m, field_on(m), multi_point_tf(),
                       render::Camera::orbit(mesh->bounds, 33, 21, 30, kSize, kSize));
}

TEST(GpuVsCpu, MeshWithHole) {
  auto m = fixtures::tet_block_with_hole(9);
  for (double& v : m.xyz) v = 2.0 * v - 1.0;
  const auto mesh = test::prepare(m);
  // Looking almost down the hole: rays leave and re-enter the mesh.
  expect_same_pictures("mesh with hole", m, field_on(m), multi_point_tf(),
                       render::Camera::orbit(mesh->bounds, 20, 70, 30, kSize, kSize));
}

TEST(GpuVsCpu, HexMeshSplitIntoTets) {
  const auto m = fixtures::block(BlockCells::hexes, 6, 6, 6, {-1, -1, -1}, {1, 1, 1});
  const auto mesh = test::prepare(m);
  expect_same_pictures("hex block split into tets", m, field_on(m), multi_point_tf(),
                       render::Camera::orbit(mesh->bounds, -40, 30, 30, kSize, kSize));
}

TEST(GpuVsCpu, EarlyTerminationAndDenseMedium) {
  const auto m = fixtures::block(BlockCells::tets, 6, 6, 6, {-1, -1, -1}, {1, 1, 1});
  const auto mesh = test::prepare(m);
  render::TransferFunction tf = multi_point_tf();
  for (auto& o : tf.opacities) o.a *= 20;  // most rays go opaque within a few tets
  expect_same_pictures("dense medium, early termination", m, field_on(m), tf,
                       render::Camera::orbit(mesh->bounds, 10, -20, 30, kSize, kSize));
}

TEST(GpuVsCpu, NaNValuesAndDataFarFromZero) {
  auto m = fixtures::block(BlockCells::wedges, 5, 5, 5, {-1, -1, -1}, {1, 1, 1});
  auto scalars = field_on(m);
  for (std::size_t i = 0; i < scalars.size(); i += 7) scalars[i] = std::nanf("");
  // Shifted by 1000: float32 evaluation must not cancel (pieces are written around their breakpoints).
  for (float& s : scalars) s += 1000.0f;
  auto tf = multi_point_tf();
  for (auto& c : tf.colors) c.x += 1000.0;
  for (auto& o : tf.opacities) o.x += 1000.0;
  const auto mesh = test::prepare(m);
  expect_same_pictures("wedges, NaN values, data near 1000", m, scalars, tf,
                       render::Camera::orbit(mesh->bounds, 60, 10, 30, kSize, kSize));
}

TEST(GpuVsCpu, EyeInsideTheMesh) {
  const auto m = fixtures::block(BlockCells::tets, 6, 6, 6, {-1, -1, -1}, {1, 1, 1});
  const auto cam = render::Camera::look_at({0.1, -0.2, 0.05}, {1, 0.5, 0.3}, {0, 0, 1}, 60, kSize, kSize);
  expect_same_pictures("eye inside the mesh", m, field_on(m), multi_point_tf(), cam);
}

TEST(GpuVsCpu, HangingNodesReenterAcrossUnmatchedFaces) {
  // One hex beside a 2x2x2 block of hexes: every face on x = 1 is unmatched, so each ray leaves
  // the mesh there and re-enters at the same depth (the re-entry slack).
  auto m = fixtures::block(BlockCells::hexes, 1, 1, 1, {0, 0, 0}, {1, 1, 1});
  const auto fine = fixtures::block(BlockCells::hexes, 2, 2, 2, {1, 0, 0}, {2, 1, 1});
  const auto base = static_cast<std::int64_t>(m.point_count());
  m.xyz.insert(m.xyz.end(), fine.xyz.begin(), fine.xyz.end());
  for (std::size_t c = 0; c < fine.cell_count(); ++c) {
    const auto* v = &fine.connectivity[8 * c];
    m.add_cell(12, {v[0] + base, v[1] + base, v[2] + base, v[3] + base, v[4] + base, v[5] + base, v[6] + base, v[7] + base});
  }
  const auto scalars = test::to_float(fixtures::sample(m, [](double x, double y, double z) { return x + y * z; }));
  render::TransferFunction tf;
  tf.colors = {{0.0, 0.1, 0.2, 0.9}, {3.0, 1.0, 0.4, 0.1}};
  tf.opacities = {{0.0, 0.5}, {3.0, 3.0}};
  const auto mesh = test::prepare(m);
  expect_same_pictures("hanging nodes", m, scalars, tf, render::Camera::orbit(mesh->bounds, 10, 15, 30, kSize, kSize));
}

}  // namespace
}  // namespace penumbra

namespace penumbra {
namespace {

// Shading (penumbra/render/shading.h) on both paths: Phong from the per-tet gradient with a key
// light, and Phong times a light field that varies across the mesh (with NaN points, which
// count as no light). Same tolerances as the unshaded scenes: the factors are computed in
// float32 on the GPU from the same inputs.
TEST(GpuVsCpu, PhongAndLightFieldShading) {
  auto m = fixtures::tet_block_with_hole(8);
  for (double& v : m.xyz) v = 2.0 * v - 1.0;
  const auto mesh = test::prepare(m);
  const auto cam = render::Camera::orbit(mesh->bounds, 47, 31, 30, kSize, kSize);
  render::RenderOptions phong;
  phong.shading.model = render::LightingModel::phong;
  phong.shading.light_direction = {0.3, -0.5, 0.8};
  expect_same_pictures("phong, key light", m, field_on(m), multi_point_tf(), cam, phong);
  phong.shading.light_direction = {0, 0, 0};
  expect_same_pictures("phong, headlight", m, field_on(m), multi_point_tf(), cam, phong);

  std::vector<float> light(3 * mesh->points.size());
  for (std::size_t i = 0; i < mesh->points.size(); ++i) {
    const Vec3d& p = mesh->points[i];
    light[3 * i] = static_cast<float>(0.5 + 0.5 * std::exp(-p.x - 1.0));
    light[3 * i + 1] = static_cast<float>(0.3 + 0.6 * (p.y + 1.0) / 2.0);
    light[3 * i + 2] = i % 97 == 0 ? std::nanf("") : 1.0f;
  }
  render::RenderOptions lit;
  lit.shading.model = render::LightingModel::light_volume;
  lit.shading.light_rgb = &light;
  lit.shading.light_direction = {-0.4, 0.2, 0.9};
  expect_same_pictures("light field", m, field_on(m), multi_point_tf(), cam, lit);
}

}  // namespace
}  // namespace penumbra

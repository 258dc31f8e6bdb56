// SPDX-License-Identifier: BSD-3-Clause
// The GPU ray caster's memory accounting, incremental field upload, argument checks and sharing.
#include <gtest/gtest.h>

#include <cmath>
#include <thread>

#include "fixtures/meshes.h"
#include "penumbra/core/error.h"
#include "penumbra/render/gpu_ray_caster.h"

namespace penumbra {
namespace {

using fixtures::BlockCells;

std::shared_ptr<const render::TetMesh> prepare(const fixtures::OwnedMesh& m) {
  return std::make_shared<const render::TetMesh>(render::prepare_tet_mesh(m.view()));
}

render::GpuOptions quiet() {
  render::GpuOptions o;
  o.log = [](const std::string&) {};
  return o;
}

render::TransferFunction ramp() {
  render::TransferFunction tf;
  tf.colors = {{0.0, 0.2, 0.3, 1.0}, {1.0, 1.0, 0.5, 0.1}};
  tf.opacities = {{0.0, 0.2}, {1.0, 3.0}};
  return tf;
}

std::vector<float> x_field(const render::TetMesh& m) {
  std::vector<float> s;
  for (const auto& p : m.points) s.push_back(static_cast<float>(0.5 + 0.5 * p.x));
  return s;
}

class GpuRayCasterTest : public ::testing::Test {
protected:
  void SetUp() override {
    if (!render::gpu_backend_compiled()) GTEST_SKIP() << "built without the GPU backend";
    device = render::GpuDevice::open(quiet());
  }
  std::shared_ptr<render::GpuDevice> device;
};

TEST_F(GpuRayCasterTest, BytesPerTetAreExactAndWithinTarget) {
  const auto mesh = prepare(fixtures::block(BlockCells::tets, 20, 20, 20, {-1, -1, -1}, {1, 1, 1}));
  render::GpuRayCaster caster(device, mesh);
  const auto s = caster.memory();
  const std::size_t tets = 6 * 20 * 20 * 20, points = 21 * 21 * 21;
  EXPECT_EQ(s.tets, tets);
  EXPECT_EQ(s.points, points);
  EXPECT_EQ(s.geometry_bytes, 12 * points + 16 * tets);  // float32 xyz, 4 int32 vertex ids
  EXPECT_EQ(s.adjacency_bytes, 16 * tets);               // 4 int32 neighbour links
  EXPECT_EQ(s.scalar_bytes, 4 * points);                 // one float32 per point
  EXPECT_EQ(s.boundary_triangles, 6u * 2 * 20 * 20);
  EXPECT_EQ(s.acceleration_bytes, 16 * s.boundary_triangles + 32 * s.bvh_nodes);
  // 32 B/tet plus 16 B per point at ~1/5.2 points per tet.
  EXPECT_NEAR(s.mesh_bytes_per_tet(), 32.0 + 16.0 * points / tets, 1e-12);
  EXPECT_LE(s.mesh_bytes_per_tet(), 64.0);
  EXPECT_LE(s.total_bytes_per_tet(), 64.0);
  std::printf("[gpu-memory] %zu tets, %zu points: %.2f B/tet geometry+adjacency+scalar, %.2f B/tet with the "
              "boundary BVH\n", s.tets, s.points, s.mesh_bytes_per_tet(), s.total_bytes_per_tet());
}

TEST_F(GpuRayCasterTest, MeshBeyondTheMemoryLimitIsAClearError) {
  render::GpuOptions o = quiet();
  o.memory_limit_bytes = 100000;
  const auto small_device = render::GpuDevice::open(o);
  const auto mesh = prepare(fixtures::block(BlockCells::tets, 12, 12, 12, {0, 0, 0}, {1, 1, 1}));
  try {
    render::GpuRayCaster caster(small_device, mesh);
    ADD_FAILURE() << "a mesh needing more than the limit was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::out_of_memory);
    EXPECT_NE(std::string(e.what()).find("the mesh (10368 tets, 2197 points) needs"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("configured limit is 0.1 MiB"), std::string::npos) << e.what();
  }
}

TEST_F(GpuRayCasterTest, OnlyChangedFieldValuesAreUploaded) {
  const auto mesh = prepare(fixtures::block(BlockCells::tets, 40, 40, 30, {-1, -1, -1}, {1, 1, 1}));
  const std::size_t points = mesh->points.size();  // 41*41*31 = 52111: four 16384-value blocks
  render::GpuRayCaster caster(device, mesh);
  const auto cam = render::Camera::orbit(mesh->bounds, 30, 20, 30, 8, 8);
  auto scalars = x_field(*mesh);
  caster.render(scalars, ramp(), cam);
  EXPECT_EQ(caster.last_scalar_upload_bytes(), 4 * points);
  caster.render(scalars, ramp(), cam);
  EXPECT_EQ(caster.last_scalar_upload_bytes(), 0u);
  scalars[20000] = 0.25f;  // inside the second block
  caster.render(scalars, ramp(), cam);
  EXPECT_EQ(caster.last_scalar_upload_bytes(), 4u * 16384);
  scalars[1] = 0.5f;
  scalars[points - 1] = 0.5f;  // the last, partial block
  caster.render(scalars, ramp(), cam);
  EXPECT_EQ(caster.last_scalar_upload_bytes(), 4u * (16384 + (points - 3 * 16384)));
}

TEST_F(GpuRayCasterTest, ChangedFieldChangesThePicture) {
  const auto mesh = prepare(fixtures::block(BlockCells::tets, 4, 4, 4, {-1, -1, -1}, {1, 1, 1}));
  render::GpuRayCaster gpu(device, mesh);
  render::CpuRayCaster cpu(mesh);
  const auto cam = render::Camera::orbit(mesh->bounds, 30, 20, 30, 24, 24);
  auto scalars = x_field(*mesh);
  gpu.render(scalars, ramp(), cam);
  for (float& s : scalars) s = 1.0f - s;  // a new step: every value changes
  const auto a = gpu.render(scalars, ramp(), cam);
  const auto b = cpu.render(scalars, ramp(), cam);
  for (std::size_t i = 0; i < a.rgba.size(); ++i) ASSERT_NEAR(a.rgba[i], b.rgba[i], 1e-4) << i;
}

TEST_F(GpuRayCasterTest, ImagesWiderThanOneDispatchTileAreStitched) {
  const auto mesh = prepare(fixtures::block(BlockCells::tets, 3, 3, 3, {-1, -1, -1}, {1, 1, 1}));
  render::GpuRayCaster gpu(device, mesh);
  render::CpuRayCaster cpu(mesh);
  // 600 x 20: two tiles across (512 + 88), rows narrower than one tile.
  const auto cam = render::Camera::look_at({0, -6, 0}, {0, 0, 0}, {0, 0, 1}, 12, 600, 20);
  const auto scalars = x_field(*mesh);
  const auto a = gpu.render(scalars, ramp(), cam);
  const auto b = cpu.render(scalars, ramp(), cam);
  ASSERT_EQ(a.width, 600);
  ASSERT_EQ(a.height, 20);
  double max_diff = 0, coverage = 0;
  for (std::size_t i = 0; i < a.rgba.size(); ++i) max_diff = std::max(max_diff, double(std::fabs(a.rgba[i] - b.rgba[i])));
  for (std::size_t i = 3; i < b.rgba.size(); i += 4) coverage += b.rgba[i];
  EXPECT_LT(max_diff, 1e-4);
  EXPECT_GT(coverage, 100.0);
}

TEST_F(GpuRayCasterTest, BadArgumentsAreRefusedByName) {
  const auto mesh = prepare(fixtures::block(BlockCells::tets, 2, 2, 2, {0, 0, 0}, {1, 1, 1}));
  render::GpuRayCaster caster(device, mesh);
  const auto cam = render::Camera::orbit(mesh->bounds, 0, 0, 30, 8, 8);
  const auto scalars = x_field(*mesh);
  auto code = [](auto&& f) {
    try {
      f();
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("GpuRayCaster"), std::string::npos) << e.what();
      return e.code();
    }
    return ErrorCode::ok;
  };
  EXPECT_EQ(code([&] { caster.render(std::vector<float>(3, 0.f), ramp(), cam); }), ErrorCode::invalid_argument);
  render::Camera bad = cam;
  bad.width = 0;
  EXPECT_EQ(code([&] { caster.render(scalars, ramp(), bad); }), ErrorCode::invalid_argument);
  render::RenderOptions opts;
  opts.early_termination_opacity = 0;
  EXPECT_EQ(code([&] { caster.render(scalars, ramp(), cam, opts); }), ErrorCode::invalid_argument);
  EXPECT_EQ(code([&] { render::GpuRayCaster(nullptr, mesh); }), ErrorCode::invalid_argument);
  EXPECT_EQ(code([&] { render::GpuRayCaster(device, nullptr); }), ErrorCode::invalid_argument);
}

TEST_F(GpuRayCasterTest, CastersShareADeviceAcrossThreads) {
  const auto m1 = prepare(fixtures::block(BlockCells::tets, 4, 4, 4, {-1, -1, -1}, {1, 1, 1}));
  const auto m2 = prepare(fixtures::block(BlockCells::hexes, 3, 3, 3, {-1, -1, -1}, {1, 1, 1}));
  render::GpuRayCaster a(device, m1), b(device, m2);
  const auto cam = render::Camera::orbit(m1->bounds, 30, 20, 30, 16, 16);
  const auto s1 = x_field(*m1), s2 = x_field(*m2);
  const auto ref1 = a.render(s1, ramp(), cam), ref2 = b.render(s2, ramp(), cam);
  render::Image r1, r2;
  std::thread t1([&] { for (int i = 0; i < 3; ++i) r1 = a.render(s1, ramp(), cam); });
  std::thread t2([&] { for (int i = 0; i < 3; ++i) r2 = b.render(s2, ramp(), cam); });
  t1.join();
  t2.join();
  EXPECT_EQ(r1.rgba, ref1.rgba);
  EXPECT_EQ(r2.rgba, ref2.rgba);
}

TEST_F(GpuRayCasterTest, ClosingOneDeviceLeavesAnotherWorking) {
  const auto mesh = prepare(fixtures::block(BlockCells::tets, 3, 3, 3, {-1, -1, -1}, {1, 1, 1}));
  const auto cam = render::Camera::orbit(mesh->bounds, 30, 20, 30, 16, 16);
  const auto scalars = x_field(*mesh);
  auto other = render::GpuDevice::open(quiet());
  render::GpuRayCaster keep(device, mesh);
  const auto before = keep.render(scalars, ramp(), cam);
  {
    render::GpuRayCaster gone(other, mesh);
    gone.render(scalars, ramp(), cam);
  }
  other.reset();  // the display is shared: it must stay initialised for `device`
  EXPECT_EQ(keep.render(scalars, ramp(), cam).rgba, before.rgba);
}

}  // namespace
}  // namespace penumbra

// SPDX-License-Identifier: BSD-3-Clause
// tests/unit/insitu/context_test.cpp -- the per-step pipeline through the C++ Context
#include <gtest/gtest.h>

#include <chrono>
#include <thread>
#include <cmath>

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

struct Scene {
  fixtures::OwnedMesh mesh = fixtures::block(BlockCells::tets, 4, 4, 4, {0, 0, 0}, {1, 1, 1});
  std::vector<double> blob = fixtures::sample(mesh, [](double x, double y, double z) {
    return std::exp(-8 * ((x - .5) * (x - .5) + (y - .5) * (y - .5) + (z - .5) * (z - .5)));
  });
};

std::vector<std::vector<std::string>> csv_rows(const std::string& dir) {
  return CinemaDatabase::parse_csv(testing::read_text(dir + "/data.csv"), "data.csv");
}

std::vector<unsigned char> image(const std::string& dir, const std::string& rel, int& w, int& h) {
  return render::read_png_rgb(dir + "/" + rel, w, h);
}

TEST(Context, RendersEveryFieldAndCameraIntoTheDatabase) {
  TempDir tmp;
  Scene s;
  Context ctx(parse_config(testing::small_config(tmp / "db")));
  ctx.publish_mesh(s.mesh.view());
  ctx.publish_field(fixtures::point_field("T", s.blob), false);
  EXPECT_TRUE(ctx.execute(0.25, 7));
  EXPECT_EQ(ctx.last_step().images, 2);
  const auto rows = csv_rows(tmp / "db");
  ASSERT_EQ(rows.size(), 3u);
  EXPECT_EQ(rows[0], (std::vector<std::string>{"time", "phi", "theta", "field", "FILE"}));
  EXPECT_EQ(rows[1], (std::vector<std::string>{"0.25", "0", "30", "T", "T/c000007_phi0_theta30.png"}));
  EXPECT_EQ(rows[2], (std::vector<std::string>{"0.25", "90", "30", "T", "T/c000007_phi90_theta30.png"}));
  int w = 0, h = 0;
  const auto rgb = image(tmp / "db", rows[1][4], w, h);
  EXPECT_EQ(w, 24);
  EXPECT_EQ(h, 20);
  // The block fills the middle of the view: its centre pixel is not the white background.
  const unsigned char* centre = &rgb[(10 * 24 + 12) * 3];
  EXPECT_LT(int(centre[0]) + centre[1] + centre[2], 3 * 250);
}

TEST(Context, UnchangedTopologyVersionSkipsPreparation) {
  TempDir tmp;
  Scene s;
  fixtures::OwnedMesh big = fixtures::block(BlockCells::hexes, 24, 24, 24, {0, 0, 0}, {1, 1, 1});
  Context ctx(parse_config(testing::small_config(tmp / "db")));
  const auto t0 = std::chrono::steady_clock::now();
  ctx.publish_mesh(big.view());
  const auto t1 = std::chrono::steady_clock::now();
  for (int i = 0; i < 10; ++i) ctx.publish_mesh(big.view());
  const auto t2 = std::chrono::steady_clock::now();
  EXPECT_EQ(ctx.mesh_preparations(), 1u);
  // Ten republishes must cost less than one preparation (each is one pass comparing the points;
  // preparing 13824 hexes takes milliseconds), a loose bound that timing noise cannot break.
  EXPECT_LT((t2 - t1).count(), (t1 - t0).count());
  big.topology_version = 2;
  ctx.publish_mesh(big.view());
  EXPECT_EQ(ctx.mesh_preparations(), 2u);
  // Same version with different counts is the solver's bug, reported rather than ignored.
  s.mesh.topology_version = 2;
  EXPECT_THROW(ctx.publish_mesh(s.mesh.view()), Error);
}

// Cells marked ghost (vtkGhostType's duplicate bit) are another rank's halo: a mesh published
// with half its cells as ghosts renders as the other half published alone.
TEST(Context, GhostCellsAreNeverDrawn) {
  TempDir tmp;
  Scene s;
  const std::size_t cells = s.mesh.cell_count();
  std::vector<std::uint8_t> ghosts(cells, 0);
  fixtures::OwnedMesh own;
  own.xyz = s.mesh.xyz;
  for (std::size_t c = 0; c < cells; ++c) {
    const auto begin = s.mesh.offsets[c], end = s.mesh.offsets[c + 1];
    double x = 0;
    for (auto k = begin; k < end; ++k) x += s.mesh.xyz[3 * static_cast<std::size_t>(s.mesh.connectivity[static_cast<std::size_t>(k)])];
    if (x / static_cast<double>(end - begin) > 0.5) {
      ghosts[c] = 1;
      continue;
    }
    own.connectivity.insert(own.connectivity.end(), s.mesh.connectivity.begin() + begin, s.mesh.connectivity.begin() + end);
    own.offsets.push_back(static_cast<std::int64_t>(own.connectivity.size()));
    own.types.push_back(s.mesh.types[c]);
  }
  MeshView with_ghosts = s.mesh.view();
  with_ghosts.ghost_cells = ghosts.data();
  std::vector<unsigned char> images[2];
  for (int k = 0; k < 2; ++k) {
    const std::string dir = tmp / (k ? "own" : "ghosts");
    Context ctx(parse_config(testing::small_config(dir)));
    ctx.publish_mesh(k ? own.view() : with_ghosts);
    ctx.publish_field(fixtures::point_field("T", s.blob), false);
    EXPECT_TRUE(ctx.execute(0.0, 0));
    int w = 0, h = 0;
    images[k] = image(dir, csv_rows(dir)[1][4], w, h);
  }
  EXPECT_EQ(images[0], images[1]);
  // Every cell a ghost: nothing of this rank's own to draw, which is named.
  std::vector<std::uint8_t> all(cells, 1);
  with_ghosts.ghost_cells = all.data();
  with_ghosts.topology_version = 7;
  Context ctx(parse_config(testing::small_config(tmp / "none")));
  try {
    ctx.publish_mesh(with_ghosts);
    ADD_FAILURE() << "expected a mesh of ghosts only to be refused";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("every cell is a ghost"), std::string::npos) << e.what();
  }
}

// A solver's x[], y[], z[] published as three arrays give the picture of the interleaved points.
TEST(Context, ThreeCoordinateArraysRenderLikeInterleavedPoints) {
  TempDir tmp;
  Scene s;
  const std::size_t n = s.mesh.point_count();
  std::vector<double> x(n), y(n), z(n);
  for (std::size_t i = 0; i < n; ++i) x[i] = s.mesh.xyz[3 * i], y[i] = s.mesh.xyz[3 * i + 1], z[i] = s.mesh.xyz[3 * i + 2];
  MeshView arrays = s.mesh.view();
  arrays.points = {nullptr, n, 0};
  const double* axes[3] = {x.data(), y.data(), z.data()};
  for (int a = 0; a < 3; ++a) arrays.axes[a] = {reinterpret_cast<const std::byte*>(axes[a]), n, sizeof(double)};
  std::vector<unsigned char> images[2];
  for (int k = 0; k < 2; ++k) {
    const std::string dir = tmp / (k ? "arrays" : "interleaved");
    Context ctx(parse_config(testing::small_config(dir)));
    ctx.publish_mesh(k ? arrays : s.mesh.view());
    ctx.publish_field(fixtures::point_field("T", s.blob), false);
    EXPECT_TRUE(ctx.execute(0.0, 0));
    if (k) ctx.publish_mesh(arrays);  // republished unchanged: accepted
    int w = 0, h = 0;
    images[k] = image(dir, csv_rows(dir)[1][4], w, h);
  }
  EXPECT_EQ(images[0], images[1]);
}

TEST(Context, UnconfiguredFieldsAreNeitherCopiedNorChecked) {
  TempDir tmp;
  Scene s;
  Context ctx(parse_config(testing::small_config(tmp / "db")));
  ctx.publish_mesh(s.mesh.view());
  std::vector<double> wrong_size(3, 1.0);
  ctx.publish_field(fixtures::point_field("pressure", wrong_size), true);
  EXPECT_EQ(ctx.held_field_count(), 0u);
  EXPECT_EQ(ctx.held_field_bytes(), 0u);
  ctx.publish_field(fixtures::point_field("T", s.blob), true);
  EXPECT_EQ(ctx.held_field_count(), 1u);
  EXPECT_EQ(ctx.held_field_bytes(), s.blob.size() * sizeof(double));
}

TEST(Context, CopiedFieldsPersistBorrowedOnesAreForgottenAfterExecute) {
  TempDir tmp;
  Scene s;
  Context ctx(parse_config(testing::small_config(tmp / "db")));
  ctx.publish_mesh(s.mesh.view());
  ctx.publish_field(fixtures::point_field("T", s.blob), false);
  ctx.execute(0, 0);
  EXPECT_EQ(ctx.held_field_count(), 0u);
  EXPECT_THROW(ctx.execute(1, 1), Error);  // borrowed field not republished
  {
    std::vector<double> copy = s.blob;
    ctx.publish_field(fixtures::point_field("T", copy), true);
    std::fill(copy.begin(), copy.end(), -1.0);  // the context holds its own copy
  }
  EXPECT_TRUE(ctx.execute(2, 2));
  EXPECT_TRUE(ctx.execute(3, 3));
  EXPECT_EQ(csv_rows(tmp / "db").size(), 1u + 2 * 3);
}

TEST(Context, FailedFieldIsSkippedOthersAreWrittenAndLaterStepsWork) {
  TempDir tmp;
  Scene s;
  Context ctx(parse_config(testing::small_config(tmp / "db", R"([{"name": "T"}, {"name": "U"}])")));
  ctx.publish_mesh(s.mesh.view());
  ctx.publish_field(fixtures::point_field("T", s.blob), false);
  try {
    ctx.execute(0, 0);
    FAIL() << "missing field U not reported";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::invalid_operation);
    EXPECT_NE(std::string(e.what()).find("field 'U' was not published for cycle 0"), std::string::npos) << e.what();
  }
  EXPECT_EQ(csv_rows(tmp / "db").size(), 1u + 2);  // T's two images are listed
  ctx.publish_field(fixtures::point_field("T", s.blob), false);
  ctx.publish_field(fixtures::point_field("U", s.blob), false);
  EXPECT_TRUE(ctx.execute(1, 1));
  EXPECT_EQ(csv_rows(tmp / "db").size(), 1u + 2 + 4);
}

TEST(Context, TriggerSkipsStepsWithoutTouchingTheDatabase) {
  TempDir tmp;
  Scene s;
  Context ctx(parse_config(testing::small_config(tmp / "db", R"([{"name": "T"}])", R"(, "trigger": {"every_cycles": 3})")));
  ctx.publish_mesh(s.mesh.view());
  int rendered = 0;
  for (int c = 0; c < 7; ++c) {
    ctx.publish_field(fixtures::point_field("T", s.blob), false);
    rendered += ctx.execute(c * 0.1, c);
  }
  EXPECT_EQ(rendered, 3);  // cycles 0, 3, 6
  EXPECT_EQ(csv_rows(tmp / "db").size(), 1u + 3 * 2);
}

/// Renders `values` once with one camera and returns the centre pixel.
std::array<int, 3> centre_pixel(const std::vector<double>& values, const std::string& field_json) {
  TempDir tmp;
  Scene s;
  Context ctx(parse_config(R"({"output": {"directory": ")" + (tmp / "db") + R"("}, "image": {"width": 9, "height": 9},
      "cameras": {"phi": [30], "theta": [20]}, "fields": [)" + field_json + "]}"));
  ctx.publish_mesh(s.mesh.view());
  ctx.publish_field(fixtures::point_field("T", values), false);
  ctx.execute(0, 0);
  int w, h;
  const auto rgb = image(tmp / "db", csv_rows(tmp / "db")[1][4], w, h);
  const unsigned char* p = &rgb[(4 * 9 + 4) * 3];
  return {p[0], p[1], p[2]};
}

TEST(Context, ConstantFieldWithAutoRangeUsesTheMiddleOfTheTransferFunction) {
  Scene s;
  // Colour red below 0.5, blue above; opacity only near x = 0.5. A constant field must show the
  // colour at x = 0.5 (purple) rather than fail or produce NaN from lo == hi.
  const std::string tf = R"({"name": "T", "transfer_function": {"colors": [[0, 1, 0, 0], [0.5, 0.5, 0, 0.5], [1, 0, 0, 1]],
                                                                 "opacities": [[0.4, 0], [0.5, 50], [0.6, 0]]}})";
  const auto p = centre_pixel(std::vector<double>(s.mesh.point_count(), 7.0), tf);
  EXPECT_GT(p[0], 50);
  EXPECT_LT(p[1], 40);
  EXPECT_GT(p[2], 50);
  EXPECT_NEAR(p[0], p[2], 8);  // 8/255: PNG rounding plus the float ray integration
}

TEST(Context, AllNanFieldRendersAsBackground) {
  Scene s;
  const auto p = centre_pixel(std::vector<double>(s.mesh.point_count(), std::nan("")), R"({"name": "T"})");
  EXPECT_EQ(p, (std::array<int, 3>{255, 255, 255}));
}

TEST(Context, RangeAndDataUnitsSelectTheColour) {
  Scene s;
  // Field 2 everywhere; fixed range [0, 4] puts it at x = 0.5; data units read x = 2 directly.
  const std::vector<double> two(s.mesh.point_count(), 2.0);
  const auto a = centre_pixel(two, R"({"name": "T", "range": [0, 4], "transfer_function": {
      "colors": [[0, 1, 0, 0], [0.5, 0, 1, 0], [1, 0, 0, 1]], "opacities": [[0, 40]]}})");
  EXPECT_GT(a[1], 200);
  const auto b = centre_pixel(two, R"({"name": "T", "transfer_function": {"x": "data",
      "colors": [[0, 1, 0, 0], [2, 0, 0, 1]], "opacities": [[0, 40]]}})");
  EXPECT_GT(b[2], 200);
  EXPECT_LT(b[0], 30);
}

TEST(Context, OpacityUnitsDiagonalAndWorldAgree) {
  Scene s;
  // The unit cube's diagonal is sqrt(3): a = 0.6 per world unit equals a = 0.6*sqrt(3) per diagonal.
  // Moderate opacity keeps the pixel sensitive to the extinction scale; 1/255 allows PNG rounding.
  const auto world = centre_pixel(s.blob, R"({"name": "T", "transfer_function": {"opacity_unit": "world",
      "colors": [[0, 0, 0, 0]], "opacities": [[0, 0.6]]}})");
  const auto diagonal = centre_pixel(s.blob, R"({"name": "T", "transfer_function": {"opacity_unit": "diagonal",
      "colors": [[0, 0, 0, 0]], "opacities": [[0, 1.0392304845413265]]}})");
  const auto thinner = centre_pixel(s.blob, R"({"name": "T", "transfer_function": {"opacity_unit": "diagonal",
      "colors": [[0, 0, 0, 0]], "opacities": [[0, 0.6]]}})");
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(world[c], diagonal[c], 1);
  EXPECT_GT(thinner[0], world[0] + 10);  // less extinction: more of the white background shows
  EXPECT_LT(world[0], 200);
}

TEST(Context, ExecuteBeforeMeshAndAfterFinalizeAreInvalidOperations) {
  TempDir tmp;
  Scene s;
  Context ctx(parse_config(testing::small_config(tmp / "db")));
  try {
    ctx.execute(0, 0);
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::invalid_operation);
  }
  EXPECT_THROW(ctx.publish_field(fixtures::point_field("T", s.blob), false), Error);
  ctx.finalize();
  EXPECT_THROW(ctx.publish_mesh(s.mesh.view()), Error);
}

// Sets an environment variable for one scope.
class ScopedEnv {
public:
  ScopedEnv(const char* name, const char* value) : m_name(name) { ::setenv(name, value, 1); }
  ~ScopedEnv() { ::unsetenv(m_name); }
  ScopedEnv(const ScopedEnv&) = delete;
  ScopedEnv& operator=(const ScopedEnv&) = delete;

private:
  const char* m_name;
};

TEST(Context, GpuBackendWithoutEglIsUnavailableAndAutoFallsBackToCpu) {
  TempDir tmp;
  const ScopedEnv no_egl("PNB_EGL_LIBRARY", "/nonexistent/libEGL.so.1");
  try {
    Context ctx(parse_config(testing::small_config(tmp / "a", R"([{"name": "T"}])", R"(, "backend": "gpu")")));
    FAIL() << "backend gpu without EGL was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::backend_unavailable);
    EXPECT_NE(std::string(e.what()).find("backend \"gpu\" is not available"), std::string::npos) << e.what();
    if (render::gpu_backend_compiled())
      EXPECT_NE(std::string(e.what()).find("cannot load the EGL library '/nonexistent/libEGL.so.1'"), std::string::npos)
          << e.what();
  }
  Context ctx(parse_config(testing::small_config(tmp / "b", R"([{"name": "T"}])", R"(, "backend": "auto")")));
  EXPECT_EQ(ctx.config().backend, Backend::cpu);
  Scene s;
  ctx.publish_mesh(s.mesh.view());
  ctx.publish_field(fixtures::point_field("T", s.blob), false);
  EXPECT_TRUE(ctx.execute(0, 0));
  EXPECT_EQ(ctx.last_step().images, 2);
}

TEST(Context, AutoTakesTheGpuOnlyWhenItIsHardware) {
  TempDir tmp;
  Context ctx(parse_config(testing::small_config(tmp / "db", R"([{"name": "T"}])", R"(, "backend": "auto")")));
  EXPECT_EQ(ctx.config().backend, render::hardware_gpu_present() ? Backend::gpu : Backend::cpu);
}

TEST(Context, SoftwareGpuIsReportedOnceInTheLog) {
  if (!render::gpu_backend_compiled() || render::hardware_gpu_present())
    GTEST_SKIP() << "needs the GPU backend on a node with only a software device";
  TempDir tmp;
  // Its own EGL setting: the process-wide device for it is opened inside this test.
  const ScopedEnv surfaceless("PNB_EGL_DEVICE", "surfaceless");
  ::testing::internal::CaptureStderr();
  for (const char* dir : {"a", "b"})
    Context(parse_config(testing::small_config(tmp / dir, R"([{"name": "T"}])", R"(, "backend": "gpu")")));
  const std::string log = ::testing::internal::GetCapturedStderr();
  auto count = [&](const std::string& needle) {
    int n = 0;
    for (auto at = log.find(needle); at != std::string::npos; at = log.find(needle, at + 1)) ++n;
    return n;
  };
  EXPECT_EQ(count("penumbra: GPU backend on Mesa surfaceless platform"), 1) << log;
  EXPECT_EQ(count("runs on a software rasteriser"), 1) << log;
}

TEST(Context, GpuBackendWritesTheCpuBackendsImages) {
  if (!render::gpu_backend_compiled()) GTEST_SKIP() << "built without the GPU backend";
  TempDir tmp;
  Scene s;
  std::vector<unsigned char> images[2];
  const char* backends[2] = {"cpu", "gpu"};
  for (int b = 0; b < 2; ++b) {
    // On a node without a GPU, "gpu" runs on Mesa's software device: that is how CI tests it.
    Context ctx(parse_config(testing::small_config(tmp / backends[b], R"([{"name": "T"}])",
                                                   std::string(R"(, "backend": ")") + backends[b] + "\"")));
    EXPECT_EQ(ctx.config().backend, b == 0 ? Backend::cpu : Backend::gpu);
    ctx.publish_mesh(s.mesh.view());
    ctx.publish_field(fixtures::point_field("T", s.blob), false);
    ASSERT_TRUE(ctx.execute(0.5, 3));
    int w = 0, h = 0;
    images[b] = image(tmp / backends[b], "T/c000003_phi90_theta30.png", w, h);
    EXPECT_EQ(w, 24);
  }
  // float32 on the GPU against float64: at most single 8-bit rounding flips (see gpu_vs_cpu_test.cpp).
  EXPECT_LT(render::rms_difference_pct(images[0], images[1]), 0.5);
  int max_diff = 0;
  for (std::size_t i = 0; i < images[0].size(); ++i) max_diff = std::max(max_diff, std::abs(images[0][i] - images[1][i]));
  EXPECT_LE(max_diff, 2);
}

TEST(Context, LookAtCamerasAddACameraColumn) {
  TempDir tmp;
  Scene s;
  Context ctx(parse_config(R"({"output": {"directory": ")" + (tmp / "db") + R"("}, "image": {"width": 8, "height": 8},
      "cameras": {"phi": [0], "theta": [0], "look_at": [{"name": "side", "eye": [0.5, -3, 0.5], "target": [0.5, 0.5, 0.5]}]},
      "fields": [{"name": "T"}]})"));
  ctx.publish_mesh(s.mesh.view());
  ctx.publish_field(fixtures::point_field("T", s.blob), false);
  ctx.execute(0, 0);
  const auto rows = csv_rows(tmp / "db");
  ASSERT_EQ(rows.size(), 3u);
  EXPECT_EQ(rows[0], (std::vector<std::string>{"time", "phi", "theta", "camera", "field", "FILE"}));
  EXPECT_EQ(rows[1][3], "orbit");
  EXPECT_EQ(rows[2], (std::vector<std::string>{"0", "-90", "0", "side", "T", "T/c000000_side.png"}));
}

TEST(Context, CellFieldsAndVectorComponentsAreRendered) {
  TempDir tmp;
  Scene s;
  Context ctx(parse_config(testing::small_config(tmp / "db", R"([{"name": "v", "component": 1}, {"name": "v"}])")));
  ctx.publish_mesh(s.mesh.view());
  std::vector<float> v(3 * s.mesh.cell_count(), 0.5f);
  FieldView f;
  f.name = "v";
  f.association = Association::cell;
  f.type = ScalarType::float32;
  f.components = 3;
  f.values = {reinterpret_cast<const std::byte*>(v.data()), s.mesh.cell_count(), 3 * sizeof(float)};
  ctx.publish_field(f, false);
  EXPECT_TRUE(ctx.execute(0, 0));
  const auto rows = csv_rows(tmp / "db");
  ASSERT_EQ(rows.size(), 5u);
  EXPECT_EQ(rows[1][3], "v_c1");
  EXPECT_EQ(rows[3][3], "v_magnitude");
  f.components = 1;
  f.values.stride_bytes = sizeof(float);
  EXPECT_THROW(ctx.publish_field(f, false), Error);  // config renders component 1
}

}  // namespace
}  // namespace penumbra::insitu

namespace penumbra::insitu {
namespace {

// "trigger": {"when": ...}: a step renders when the statistics of the step before satisfy it;
// pnb_step_needs knows so before the step's arrays exist, and lists the watched field every step.
TEST(Context, TriggerWhenRendersOnTheFieldsStatistics) {
  TempDir tmp;
  const auto mesh = fixtures::block(BlockCells::tets, 2, 2, 2, {0, 0, 0}, {1, 1, 1});
  Context ctx(parse_config(testing::small_config(tmp / "db", R"([{"name": "T"}])",
                                                 R"(, "trigger": {"when": "max(P) > 2.5"})")));
  ctx.publish_mesh(mesh.view());
  std::vector<std::int64_t> rendered;
  for (int k = 0; k < 6; ++k) {
    const StepNeeds needs = ctx.step_needs(k, k);
    EXPECT_EQ(needs.fields, needs.renders ? (std::vector<std::string>{"T", "P"}) : (std::vector<std::string>{"P"}));
    // P's maximum is k: the step after the first above 2.5 (k = 3) renders, and every one after.
    const auto p = fixtures::sample(mesh, [k](double x, double, double) { return k * x; });
    const auto t = fixtures::sample(mesh, [](double x, double y, double) { return x + y; });
    ctx.publish_field(fixtures::point_field("P", p), false);
    ctx.publish_field(fixtures::point_field("T", t), false);
    if (ctx.execute(k, k)) rendered.push_back(k);
    EXPECT_EQ(needs.renders, !rendered.empty() && rendered.back() == k) << k;
  }
  EXPECT_EQ(rendered, (std::vector<std::int64_t>{4, 5}));
  // The watched field missing from a step: a clear failure naming it.
  const auto t = fixtures::sample(mesh, [](double x, double, double) { return x; });
  ctx.publish_field(fixtures::point_field("T", t), false);
  try {
    ctx.execute(6, 6);
    ADD_FAILURE() << "a step without the trigger's field passed";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("trigger.when reads field 'P'"), std::string::npos) << e.what();
  }
}

TEST(Context, TriggerWhenIsCheckedWhenTheConfigIsRead) {
  try {
    parse_config(testing::small_config("/tmp/x", R"([{"name": "T"}])", R"(, "trigger": {"when": "max(T) >> 2"})"));
    ADD_FAILURE() << "a malformed expression was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("config: trigger.when: "), std::string::npos) << e.what();
  }
  EXPECT_THROW(parse_config(testing::small_config("/tmp/x", R"([{"name": "T"}])", R"(, "trigger": {"when": 3})")), Error);
}

}  // namespace
}  // namespace penumbra::insitu

namespace penumbra::insitu {
namespace {

// "max_share": the share is measured from the first step's return on. A solver that spends no
// time of its own between steps is then above any share after its second image and renders no
// more; one that spends 60 ms per step keeps rendering.
TEST(Context, MaxShareThinsTheImagesOfASolverThatDoesLittleElse) {
  const auto mesh = fixtures::block(BlockCells::tets, 2, 2, 2, {0, 0, 0}, {1, 1, 1});
  const auto t = fixtures::sample(mesh, [](double x, double y, double) { return x + y; });
  for (const int solver_ms : {0, 60}) {
    TempDir tmp;
    Context ctx(parse_config(testing::small_config(tmp / "db", R"([{"name": "T"}])",
                                                   R"(, "trigger": {"every_cycles": 1, "max_share": 0.5})")));
    ctx.publish_mesh(mesh.view());
    int rendered = 0;
    for (int k = 0; k < 4; ++k) {
      std::this_thread::sleep_for(std::chrono::milliseconds(solver_ms));
      ctx.publish_field(fixtures::point_field("T", t), false);
      const bool asked = ctx.step_needs(k, k).renders;
      const bool did = ctx.execute(k, k);
      EXPECT_EQ(asked, did) << "solver " << solver_ms << " ms, step " << k;
      rendered += did;
    }
    if (solver_ms == 0) {
      EXPECT_EQ(rendered, 2);
      EXPECT_GT(ctx.execute_share(), 0.5);
    } else {
      EXPECT_EQ(rendered, 4);
      EXPECT_LT(ctx.execute_share(), 0.5);
    }
  }
}

}  // namespace
}  // namespace penumbra::insitu

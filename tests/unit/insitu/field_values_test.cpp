// SPDX-License-Identifier: BSD-3-Clause
// tests/unit/insitu/field_values_test.cpp -- a field of any finite double magnitude and offset
// renders like its normalised version: the range and the normalisation happen in double before
// anything is narrowed to float (Context::StepField). Bound as for the mesh transformations
// (tests/accuracy/invariance.h): RMS at most 0.02 % of 255, no 8-bit level off by more than 2.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include "cinema_database.h"
#include "config.h"
#include "context.h"
#include "fixtures/meshes.h"
#include "penumbra/core/error.h"
#include "penumbra/insitu/stored_run.h"
#include "penumbra/render/gpu_ray_caster.h"
#include "penumbra/render/image.h"
#include "test_util.h"

namespace penumbra::insitu {
namespace {

using testing::TempDir;

const fixtures::OwnedMesh& mesh() {
  static const fixtures::OwnedMesh m = fixtures::tet_block_with_hole(7);
  return m;
}

/// A smooth field in [-1, 1] on the hole block.
std::vector<double> base_field() {
  return fixtures::sample(mesh(), [](double x, double y, double z) {
    return std::sin(5.0 * x + 0.3) * std::cos(4.0 * y - 0.2) * (0.6 + 0.4 * z);
  });
}

/// One step of `values` on `view` through a Context with `backend` and `lighting`; the image's RGB.
std::vector<unsigned char> render_step_on(const MeshView& view, const std::string& dir, const std::vector<double>& values,
                                          const std::string& backend, const std::string& lighting,
                                          const std::string& transfer_function) {
  Context ctx(parse_config(R"({"output": {"directory": ")" + dir + R"("}, "backend": ")" + backend + R"(",
      "image": {"width": 48, "height": 40, "background": [0, 0, 0]},
      "cameras": {"phi": [-60], "theta": [35]},
      "fields": [{"name": "T", "transfer_function": )" + transfer_function + R"(}], "lighting": )" + lighting + "}"));
  ctx.publish_mesh(view);
  ctx.publish_field(fixtures::point_field("T", values), false);
  EXPECT_TRUE(ctx.execute(0.0, 1));
  const auto rows = CinemaDatabase::parse_csv(testing::read_text(dir + "/data.csv"), "data.csv");
  int w = 0, h = 0;
  return render::read_png_rgb(dir + "/" + rows.at(1).back(), w, h);
}

std::vector<unsigned char> render_step(const std::string& dir, const std::vector<double>& values, const std::string& backend,
                                       const std::string& lighting, const std::string& transfer_function) {
  return render_step_on(mesh().view(), dir, values, backend, lighting, transfer_function);
}

std::string colours_and_opacities(double lo, double hi) {
  char text[400];
  std::snprintf(text, sizeof text, R"("colors": [[%.17g, 0.1, 0.2, 0.9], [%.17g, 0.9, 0.9, 0.3], [%.17g, 1, 0.2, 0.1]],
      "opacities": [[%.17g, 0.5], [%.17g, 6], [%.17g, 1]])",
                lo, lo + 0.5 * (hi - lo), hi, lo, lo + 0.7 * (hi - lo), hi);
  return text;
}

void expect_same_images(const std::string& backend, const std::string& model, const std::string& lighting) {
  TempDir tmp;
  const std::vector<double> v = base_field();
  const std::string normalized = "{" + colours_and_opacities(0, 1) + "}";
  const auto reference = render_step(tmp / "reference", v, backend, lighting, normalized);
  const double lo = *std::min_element(v.begin(), v.end()), hi = *std::max_element(v.begin(), v.end());
  int case_index = 0;
  for (double magnitude : {1e-300, 1e-40, 1e40, 1e300})
    for (double offset : {0.0, 1e6, 1e9}) {
      // a (v + offset * 2): values of size `magnitude` whose range (2a) is 1/offset of their size.
      const double a = magnitude / (1 + 2 * offset);
      std::vector<double> t(v.size());
      for (std::size_t i = 0; i < v.size(); ++i) t[i] = a * (v[i] + offset * 2);
      for (const bool data_units : {false, true}) {
        // The same transfer function in data units: its points moved like the values (the
        // normalised one spans the field's own range).
        const std::string tf =
            data_units ? R"({"x": "data", )" + colours_and_opacities(a * (lo + offset * 2), a * (hi + offset * 2)) + "}" : normalized;
        const auto image = render_step(tmp / std::to_string(case_index++), t, backend, lighting, tf);
        int worst = 0;
        for (std::size_t i = 0; i < image.size(); ++i) worst = std::max(worst, std::abs(int(image[i]) - int(reference[i])));
        const double rms = render::rms_difference_pct(image, reference);
        std::printf("[field-values] %s, %s, magnitude %g, offset %g x range, x %s: rms %.4f %%, max %d levels\n",
                    backend.c_str(), model.c_str(), magnitude, offset, data_units ? "data" : "normalized", rms, worst);
        EXPECT_LE(rms, 0.02) << magnitude << " " << offset << " " << data_units;
        EXPECT_LE(worst, 2) << magnitude << " " << offset << " " << data_units;
      }
    }
}

TEST(FieldValues, AnyMagnitudeAndOffsetRendersLikeTheNormalisedFieldOnTheCpu) {
  expect_same_images("cpu", "phong", R"({"model": "phong"})");
}

TEST(FieldValues, AnyMagnitudeAndOffsetRendersLikeTheNormalisedFieldWithTheLightVolume) {
  expect_same_images("cpu", "light volume", R"({"model": "light-volume", "level0_resolution": 16,
      "lights": [{"type": "directional", "direction": [1, 0.3, -0.5]}]})");
}

TEST(FieldValues, AnyMagnitudeAndOffsetRendersLikeTheNormalisedFieldOnTheGpu) {
  if (!render::gpu_backend_compiled()) GTEST_SKIP() << "built without the GPU backend";
  expect_same_images("gpu", "light volume", R"({"model": "light-volume", "level0_resolution": 16,
      "lights": [{"type": "directional", "direction": [1, 0.3, -0.5]}]})");
}

TEST(FieldValues, OcclusionSeesTheNormalisedField) {
  expect_same_images("cpu", "occlusion", R"({"model": "occlusion", "occlusion": {"grid": 24, "volume_resolution": 12}})");
}

// A constant field sits at the middle of its widened range, whatever its value, up to the largest
// doubles (where the widened range is held at them): never a blank image.
TEST(FieldValues, AConstantFieldOfAnyMagnitudeShowsAsAConstant) {
  TempDir tmp;
  const std::string tf = "{" + colours_and_opacities(0, 1) + "}";
  const auto middle = render_step(tmp / "one", std::vector<double>(base_field().size(), 1.0), "cpu", R"({"model": "none"})", tf);
  long sum = 0;
  for (unsigned char c : middle) sum += c;
  ASSERT_GT(sum, 0) << "the constant field must show";
  int index = 0;
  for (double c : {0.0, 1e-300, -1e300, 1.7e308, -1.7e308}) {
    const auto image = render_step(tmp / std::to_string(index++), std::vector<double>(base_field().size(), c), "cpu",
                                   R"({"model": "none"})", tf);
    long s = 0;
    for (unsigned char v : image) s += v;
    EXPECT_GT(s, sum / 4) << c;  // shown, not blank (the value sits at 0.5 or, near the limit, beside it)
  }
}

/// Step `step` of a drifting, growing field: a (v (1 + 0.1 step) + 2 offset + 0.05 step).
std::vector<double> drifting_step(const std::vector<double>& v, double a, double offset, int step) {
  std::vector<double> t(v.size());
  for (std::size_t i = 0; i < v.size(); ++i) t[i] = a * (v[i] * (1 + 0.1 * step) + offset * 2 + 0.05 * step);
  return t;
}

/// Records `steps` steps of drifting_step through a Context whose store keeps them at a
/// range-relative bound `bound` in windows of 8; returns the store's segment directory.
std::string store_steps(const std::string& dir, const std::vector<double>& v, double a, double offset, int steps,
                        double bound = 1e-3) {
  Context ctx(parse_config(testing::small_config(dir + "/db", R"([{"name": "T"}])",
                                                 R"(, "store": {"directory": ")" + dir + R"(/store", "window": 8,
                                                     "error_bound": {"relative": )" + std::to_string(bound) + "}}")));
  ctx.publish_mesh(mesh().view());
  for (int s = 0; s < steps; ++s) {
    const std::vector<double> values = drifting_step(v, a, offset, s);  // borrowed until execute returns
    ctx.publish_field(fixtures::point_field("T", values), false);
    EXPECT_TRUE(ctx.execute(0.1 * s, s));
  }
  return dir + "/store/segment-000";
}

// The store keeps each window in float32 around a double offset and scale (compression::ValueMap):
// a field of any magnitude whose offset dwarfs its variation comes back within its error bound,
// in its own units: 1e-3 of the range seen up to the end of the value's window (the streaming
// encoder's range-relative bound; windows of 8 steps).
TEST(FieldValues, TheStoreHoldsItsBoundForFieldsOfAnyMagnitudeAndOffset) {
  TempDir tmp;
  const std::vector<double> v = base_field();
  int case_index = 0;
  for (double magnitude : {1e-300, 1.0, 1e40, 1e300})
    for (double offset : {0.0, 1e9}) {
      const double a = magnitude / (1 + 2 * offset);
      const int steps = 12;
      const auto run = StoredRun::open(store_steps(tmp / std::to_string(case_index++), v, a, offset, steps));
      ASSERT_EQ(run->step_count(), std::size_t(steps));
      std::vector<double> back, lo(steps), hi(steps);
      for (int s = 0; s < steps; ++s) {
        const std::vector<double> t = drifting_step(v, a, offset, s);
        lo[s] = std::min(*std::min_element(t.begin(), t.end()), s ? lo[s - 1] : t[0]);
        hi[s] = std::max(*std::max_element(t.begin(), t.end()), s ? hi[s - 1] : t[0]);
      }
      for (int s = 0; s < steps; ++s) {
        const int window_end = std::min(s / 8 * 8 + 7, steps - 1);
        const double bound = 1e-3 * (hi[window_end] - lo[window_end]);
        run->read("T", s, back);
        const std::vector<double> truth = drifting_step(v, a, offset, s);
        double worst = 0;
        for (std::size_t i = 0; i < truth.size(); ++i) worst = std::max(worst, std::fabs(back[i] - truth[i]));
        EXPECT_LE(worst, bound) << "magnitude " << magnitude << ", offset " << offset << ", step " << s;
        EXPECT_GT(worst, 0.01 * bound) << "a lossy store that hardly loses anything is suspect";
      }
    }
}

// The replayed history renders like the exact field, whatever the field's magnitude and offset
// (same tolerance as in situ), at a bound of 1e-6 of the range: well below an 8-bit level of
// colour and of opacity over this transfer function's steepest segment.
TEST(FieldValues, TheStoresReplayRendersLikeTheExactField) {
  TempDir tmp;
  const std::vector<double> v = base_field();
  const std::string tf = "{" + colours_and_opacities(0, 1) + "}", lighting = R"({"model": "phong"})";
  const int step = 5;
  const std::vector<double> exact = drifting_step(v, 1, 0, step);
  const auto reference = render_step(tmp / "exact", exact, "cpu", lighting, tf);
  int case_index = 0;
  for (double magnitude : {1e-300, 1.0, 1e40, 1e300}) {
    const double offset = magnitude == 1 ? 0 : 1e9, a = magnitude / (1 + 2 * offset);
    std::vector<double> back;
    StoredRun::open(store_steps(tmp / std::to_string(case_index), v, a, offset, 8, 1e-6))->read("T", step, back);
    const auto image = render_step(tmp / (std::to_string(case_index++) + "-image"), back, "cpu", lighting, tf);
    int worst = 0;
    for (std::size_t i = 0; i < image.size(); ++i) worst = std::max(worst, std::abs(int(image[i]) - int(reference[i])));
    const double rms = render::rms_difference_pct(image, reference);
    std::printf("[field-values] replay, magnitude %g, offset %g x range: rms %.4f %%, max %d levels\n", magnitude, offset, rms, worst);
    EXPECT_LE(rms, 0.02) << magnitude;
    EXPECT_LE(worst, 2) << magnitude;
  }
}

// A run on a mesh scaled by 1e-9 or 1e9 and moved by 1e7 of its diagonals replays (stored mesh
// in double, stored values through the store at 1e-6 of the range) to the picture of the
// untransformed run's replay, on the CPU with the light volume and on the GPU unlit.
TEST(FieldValues, TheStoresReplayIsTheSamePictureAtAnyScaleAndOffsetOfTheMesh) {
  TempDir tmp;
  const std::vector<double> v = base_field();
  const std::string tf = "{" + colours_and_opacities(0, 1) + "}";
  const std::string light_volume = R"({"model": "light-volume", "level0_resolution": 16,
      "lights": [{"type": "directional", "direction": [1, 0.3, -0.5]}]})";
  int case_index = 0;
  auto replayed = [&](double scale, double shift_in_diagonals, const std::string& backend, const std::string& lighting) {
    fixtures::OwnedMesh m = mesh();
    const double diagonal = std::sqrt(3.0) * scale;  // the block spans the unit cube
    for (double& x : m.xyz) x = x * scale + shift_in_diagonals * diagonal;
    const std::string dir = tmp / std::to_string(case_index++);
    {
      Context ctx(parse_config(testing::small_config(dir + "/db", R"([{"name": "T"}])",
                                                     R"(, "store": {"directory": ")" + dir + R"(/store", "error_bound": {"relative": 1e-6}})")));
      ctx.publish_mesh(m.view());
      ctx.publish_field(fixtures::point_field("T", v), false);
      EXPECT_TRUE(ctx.execute(0.0, 0));
    }
    const auto run = StoredRun::open(dir + "/store/segment-000");
    std::vector<double> back;
    run->read("T", 0, back);
    return render_step_on(run->mesh(), dir + "/replay", back, backend, lighting, tf);
  };
  for (const auto& [backend, lighting] : {std::pair<std::string, std::string>{"cpu", light_volume}, {"gpu", R"({"model": "none"})"}}) {
    if (backend == "gpu" && !render::gpu_backend_compiled()) continue;
    const auto reference = replayed(1, 0, backend, lighting);
    ASSERT_GT(*std::max_element(reference.begin(), reference.end()), 64) << "the replayed picture must show the field";
    for (const auto& [scale, shift] : {std::pair{1e-9, 1e7}, std::pair{1e9, 1e7}, std::pair{1e-15, 0.0}}) {
      const auto image = replayed(scale, shift, backend, lighting);
      int worst = 0;
      for (std::size_t i = 0; i < image.size(); ++i) worst = std::max(worst, std::abs(int(image[i]) - int(reference[i])));
      const double rms = render::rms_difference_pct(image, reference);
      std::printf("[field-values] replay on %s, mesh x %g moved %g diagonals: rms %.4f %%, max %d levels\n", backend.c_str(),
                  scale, shift, rms, worst);
      EXPECT_LE(rms, 0.02) << backend << " " << scale << " " << shift;
      EXPECT_LE(worst, 2) << backend << " " << scale << " " << shift;
    }
  }
}

// A step that drifted so far from its window's first step that float32 around that step's
// reference cannot hold it within an absolute bound (1e12 away, where float32's spacing is 65536,
// against a bound of 1e-3) is refused, naming the field, the cycle and the drift; the step's
// images are still written and the steps before it stay stored.
TEST(FieldValues, TheStoreRefusesAStepThatDriftedFarBeyondItsWindowsFirst) {
  TempDir tmp;
  const std::vector<double> v = base_field();
  {
    Context ctx(parse_config(testing::small_config(tmp / "db", R"([{"name": "T"}])",
                                                   R"(, "store": {"directory": ")" + (tmp / "store") + R"(", "window": 8,
                                                       "error_bound": {"absolute": 0.001}})")));
    ctx.publish_mesh(mesh().view());
    ctx.publish_field(fixtures::point_field("T", v), false);
    EXPECT_TRUE(ctx.execute(0.0, 0));
    std::vector<double> far(v);
    for (double& x : far) x += 1e12;
    ctx.publish_field(fixtures::point_field("T", far), false);
    try {
      ctx.execute(0.1, 1);
      ADD_FAILURE() << "expected the store to refuse the step";
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ErrorCode::invalid_argument);
      for (const char* part : {"field 'T'", "cycle 1", "drifted too far within one window"})
        EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
    }
    const auto rows = CinemaDatabase::parse_csv(testing::read_text(tmp / "db/data.csv"), "data.csv");
    EXPECT_EQ(rows.size(), 5u);  // header and both steps' two images
  }
  const auto run = StoredRun::open(tmp / "store/segment-000");
  ASSERT_EQ(run->step_count(), 1u);
  std::vector<double> back;
  run->read("T", 0, back);
  for (std::size_t i = 0; i < v.size(); ++i) ASSERT_NEAR(back[i], v[i], 1e-3) << i;
}

}  // namespace
}  // namespace penumbra::insitu

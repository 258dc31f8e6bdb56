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
#include <vector>

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

/// One step of `values` through a Context with `backend` and `lighting`; the image's RGB.
std::vector<unsigned char> render_step(const std::string& dir, const std::vector<double>& values, const std::string& backend,
                                       const std::string& lighting, const std::string& transfer_function) {
  Context ctx(parse_config(R"({"output": {"directory": ")" + dir + R"("}, "backend": ")" + backend + R"(",
      "image": {"width": 48, "height": 40, "background": [0, 0, 0]},
      "cameras": {"phi": [-60], "theta": [35]},
      "fields": [{"name": "T", "transfer_function": )" + transfer_function + R"(}], "lighting": )" + lighting + "}"));
  ctx.publish_mesh(mesh().view());
  ctx.publish_field(fixtures::point_field("T", values), false);
  EXPECT_TRUE(ctx.execute(0.0, 1));
  const auto rows = CinemaDatabase::parse_csv(testing::read_text(dir + "/data.csv"), "data.csv");
  int w = 0, h = 0;
  return render::read_png_rgb(dir + "/" + rows.at(1).back(), w, h);
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

// The store keeps float32 values: a field beyond float32's range is refused there with the point
// and the limit, while the step's images (rendered from the double values) are still written.
TEST(FieldValues, TheStoreRefusesValuesBeyondFloat32AndTheImagesAreStillWritten) {
  TempDir tmp;
  std::vector<double> v = base_field();
  for (double& x : v) x = 1e40 * (x + 2);
  Context ctx(parse_config(testing::small_config(tmp / "db", R"([{"name": "T"}])",
                                                 R"(, "store": {"directory": ")" + (tmp / "store") + R"("})")));
  ctx.publish_mesh(mesh().view());
  ctx.publish_field(fixtures::point_field("T", v), false);
  try {
    ctx.execute(0.0, 1);
    ADD_FAILURE() << "expected the store to refuse the values";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::invalid_argument);
    EXPECT_NE(std::string(e.what()).find("field 'T'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("beyond float32's range"), std::string::npos) << e.what();
  }
  const auto rows = CinemaDatabase::parse_csv(testing::read_text(tmp / "db/data.csv"), "data.csv");
  EXPECT_EQ(rows.size(), 3u);  // header and the two cameras' images
}

// A field whose offset dwarfs its variation loses the variation in float32, which the store keeps:
// refused beyond the error bound (here 1e-3 of the range), stored within it.
TEST(FieldValues, TheStoreRefusesAFieldThatFloat32CannotHoldWithinItsBound) {
  TempDir tmp;
  const std::vector<double> v = base_field();
  for (const double offset : {1e2, 1e9}) {
    std::vector<double> t(v.size());
    for (std::size_t i = 0; i < v.size(); ++i) t[i] = v[i] + 2 * offset;  // range about 2
    const std::string dir = tmp / std::to_string(static_cast<long long>(offset));
    Context ctx(parse_config(testing::small_config(dir + "/db", R"([{"name": "T"}])",
                                                   R"(, "store": {"directory": ")" + dir + R"(/store", "error_bound": {"relative": 0.001}})")));
    ctx.publish_mesh(mesh().view());
    ctx.publish_field(fixtures::point_field("T", t), false);
    if (offset < 1e3) {
      EXPECT_TRUE(ctx.execute(0.0, 1));  // float32 resolves 2e2 to 1.5e-5: within 2e-3
      continue;
    }
    try {
      ctx.execute(0.0, 1);
      ADD_FAILURE() << "expected the store to refuse the field";
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ErrorCode::invalid_argument);
      EXPECT_NE(std::string(e.what()).find("float32, in which the store keeps values, moves them by up to"), std::string::npos)
          << e.what();
    }
  }
}

}  // namespace
}  // namespace penumbra::insitu

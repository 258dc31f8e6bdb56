// SPDX-License-Identifier: BSD-3-Clause
// tests/unit/compression/value_map_test.cpp -- fields of any finite magnitude and offset kept in
// float32 pages around a double offset and power-of-two scale per window (format version 7).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

#include "crc32_reference.h"
#include "expect_error.h"
#include "page_format.h"
#include "penumbra/compression/pager.h"
#include "penumbra/compression/streaming_encoder.h"
#include "penumbra/compression/value_map.h"
#include "penumbra/compression/version.h"
#include "temp_path.h"

namespace penumbra::compression {
namespace {

using testing::crc32_reference;
using testing::temp_path;

constexpr std::uint64_t kVertices = 700;

/// Step `s` of a smooth, drifting field: a (sin-cos pattern (1 + 0.1 s) + 0.05 s) + c.
std::vector<double> field_step(double a, double c, int s) {
  std::vector<double> v(kVertices);
  for (std::uint64_t i = 0; i < kVertices; ++i)
    v[i] = a * (std::sin(0.37 * double(i)) * std::cos(0.011 * double(i)) * (1 + 0.1 * s) + 0.05 * s) + c;
  return v;
}

CodecParams params(ErrorBound bound) {
  CodecParams p;
  p.window = 8;
  p.codebook_size = 32;
  p.bound = bound;
  p.entropy_level = 0;  // payloads as they are, for the byte edits below
  return p;
}

/// Pushes `steps` steps of field_step(a, c) in double; leaves the file unfinished when asked.
void write_steps(const std::string& path, double a, double c, int steps, ErrorBound bound, bool finish = true) {
  StreamingOptions o;
  o.path = path;
  o.field_name = "f";
  o.vertex_count = kVertices;
  o.codec = params(bound);
  StreamingEncoder encoder(o);
  for (int s = 0; s < steps; ++s) {
    const std::vector<double> v = field_step(a, c, s);
    encoder.push(0.5 * s, v.data());
  }
  if (finish) encoder.finish();
}

double worst_error(const std::vector<double>& a, const std::vector<double>& b) {
  double worst = 0;
  for (std::size_t i = 0; i < a.size(); ++i) worst = std::max(worst, std::fabs(a[i] - b[i]));
  return worst;
}

// Every step stores within [-2, 2] with float32's relative precision of its half-range (2^-24
// of a value in [1, 2), doubled for the rounding of the subtraction), and a constant step exactly.
TEST(ValueMap, FitStoresAStepOfAnyMagnitudeAndOffsetWithItsRangesPrecision) {
  const double big = std::numeric_limits<double>::max();
  const std::vector<std::vector<double>> steps = {
      {0.0, 1.0, 0.5},           {1e300, 1e300 * (1 + 1e-9)}, {-big, big, 0.0},   {1e-310, 3e-310},
      {2.5, 2.5, 2.5},           {-1e300, -1e300},            {0.0, 0.0},          {1e9 + 0.25, 1e9 - 0.25, 1e9},
      {-7e-300, 5e-300, 1e-301}, {std::nan(""), 4.0, 8.0}};
  for (const auto& values : steps) {
    const ValueMap map = ValueMap::fit(values.data(), values.size());
    ASSERT_TRUE(map.valid()) << values[1];
    double lo = big, hi = -big;
    for (double v : values)
      if (std::isfinite(v)) lo = std::min(lo, v), hi = std::max(hi, v);
    const double half = hi / 2 - lo / 2;
    for (double v : values) {
      if (!std::isfinite(v)) continue;
      const float x = map.stored(v);
      EXPECT_LE(std::fabs(x), 2.f) << v;
      EXPECT_LE(std::fabs(map.value(x) - v), 0x1p-23 * half) << v;
    }
  }
  EXPECT_TRUE(ValueMap::fit(steps[6].data(), 2).identity());  // zeros need nothing
}

// A field beyond float32 or far from zero against its variation keeps the error bound in its own
// units; the float32 readers see its values narrowed, the double readers what the store holds.
TEST(ValueMap, DoubleFieldsKeepTheirBoundAtAnyMagnitudeAndOffset) {
  for (const double magnitude : {1e-300, 1.0, 1e40, 1e300})
    for (const double c_in_ranges : {0.0, 1e9}) {
      // Values of size `magnitude` whose range (about 2a) is 1/c_in_ranges of their size.
      const double a = magnitude / (1 + 2 * c_in_ranges), c = c_in_ranges * 2 * a;
      for (const ErrorBound bound : {ErrorBound{BoundKind::absolute, 1e-4 * a}, ErrorBound{BoundKind::range_relative, 1e-3}}) {
        const std::string path = temp_path("mapped.pnbf");
        write_steps(path, a, c, 12, bound);
        const auto field = CompressedField::open(path);
        EXPECT_EQ(field->format_version(), 7u);
        EXPECT_EQ(field->step_count(), 12u);
        // At least the range of step 0 (about 1.6 a, at c) and at most the last step's.
        EXPECT_LT(field->value_min(), c - 0.5 * a);
        EXPECT_GT(field->value_max(), c + 0.5 * a);
        Pager pager(field);
        std::vector<double> direct(kVertices), paged(kVertices);
        std::vector<float> narrowed(kVertices);
        double lo = c, hi = c;  // of the steps so far
        std::vector<double> window_range(12);
        for (int s = 0; s < 12; ++s) {
          const auto v = field_step(a, c, s);
          lo = std::min(lo, *std::min_element(v.begin(), v.end()));
          hi = std::max(hi, *std::max_element(v.begin(), v.end()));
          window_range[s] = hi - lo;
        }
        for (int s = 0; s < 12; ++s) {
          field->read_step(s, direct.data());
          pager.read_step(s, paged.data());
          field->read_step(s, narrowed.data());
          ASSERT_EQ(0, std::memcmp(direct.data(), paged.data(), kVertices * 8)) << s;
          for (std::uint64_t i = 0; i < kVertices; ++i) ASSERT_EQ(narrowed[i], float(direct[i])) << i;
          // The range-relative bound is over the range seen up to the end of the step's window.
          const double allowed =
              bound.kind == BoundKind::absolute ? bound.value : 1e-3 * window_range[std::min(s / 8 * 8 + 7, 11)];
          const double worst = worst_error(direct, field_step(a, c, s));
          EXPECT_LE(worst, allowed) << a << " " << c_in_ranges << " " << s;
          EXPECT_GT(worst, 0.01 * allowed) << "a lossy page that loses nothing is suspect";
        }
      }
    }
}

// A run that dies leaves its finished pages readable, their maps taken from the pages themselves.
TEST(ValueMap, AnUnfinishedFileRecoversItsPagesMaps) {
  const std::string path = temp_path("unfinished.pnbf");
  const double a = 1e40, c = 2e49;
  write_steps(path, a, c, 12, {BoundKind::absolute, 1e-4 * a}, false);
  const auto field = CompressedField::open(path + ".partial", {true});
  ASSERT_EQ(field->step_count(), 8u);  // the first window; the second was never finished
  EXPECT_FALSE(field->page(0).map.identity());
  std::vector<double> back(kVertices);
  for (int s = 0; s < 8; ++s) {
    field->read_step(s, back.data());
    EXPECT_LE(worst_error(back, field_step(a, c, s)), 1e-4 * a) << s;
  }
}

// A step that drifted far beyond its window's first step, where float32 around that step cannot
// hold the bound, is refused and not recorded; the window goes on from the steps before it.
TEST(ValueMap, AStepThatDriftedBeyondItsWindowsMapIsRefused) {
  const std::string path = temp_path("drift.pnbf");
  StreamingOptions o;
  o.path = path;
  o.vertex_count = kVertices;
  o.codec = params({BoundKind::absolute, 1e-3});
  StreamingEncoder encoder(o);
  const std::vector<double> first = field_step(1, 0, 0), far = field_step(1, 1e12, 1), next = field_step(1, 0, 1);
  encoder.push(0, first.data());
  testing::expect_error([&] { encoder.push(1, far.data()); }, ErrorCode::invalid_argument,
                        {"step 1", "vertex 0", "drifted too far within one window", "half the error bound"}, "a drift of 1e12");
  encoder.push(1, next.data());
  encoder.finish();
  const auto field = CompressedField::open(path);
  ASSERT_EQ(field->step_count(), 2u);
  std::vector<double> back(kVertices);
  field->read_step(1, back.data());
  EXPECT_LE(worst_error(back, next), 1e-3);
}

// Older versions have no room for a map: a mapped page is refused rather than written wrong.
TEST(ValueMap, OlderFormatVersionsCannotHoldAMappedPage) {
  const std::string path = temp_path("page.pnbf");
  write_steps(path, 1e40, 0, 8, {});
  const auto page = CompressedField::open(path)->load_page(0);
  ASSERT_FALSE(page->map.identity());
  testing::expect_error([&] { detail::serialize_page(*page, 0, 6); }, ErrorCode::invalid_argument,
                        {"format version 6", "offset or scaled"}, "a mapped page at version 6");
  EXPECT_NO_THROW(detail::serialize_page(*page, 0, kContainerFormatVersion));
}

// A map whose scale is not a power of two (or whose offset is not finite) is a corrupt page, even
// under valid checksums.
TEST(ValueMap, ACorruptMapIsRejectedEvenUnderValidChecksums) {
  const std::string path = temp_path("map.pnbf"), bad = temp_path("map-bad.pnbf");
  write_steps(path, 1e40, 0, 8, {});
  const auto field = CompressedField::open(path);
  auto bytes = testing::read_file(path);
  const std::size_t page = field->page(0).offset, payload = page + 64, scale_at = payload + 16 + 8;
  const double three = 3;
  std::memcpy(bytes.data() + scale_at, &three, 8);
  const std::uint32_t payload_crc = crc32_reference(bytes.data() + payload, field->page(0).bytes - 64);
  std::memcpy(bytes.data() + page + 44, &payload_crc, 4);
  const std::uint32_t header_crc = crc32_reference(bytes.data() + page, 60);
  std::memcpy(bytes.data() + page + 60, &header_crc, 4);
  testing::write_file(bad, bytes.data(), bytes.size());
  testing::expect_error([&] { CompressedField::open(bad)->load_page(0); }, ErrorCode::io_error, {"page 0", "value map is corrupt"},
                        "a scale of 3");
}

}  // namespace
}  // namespace penumbra::compression

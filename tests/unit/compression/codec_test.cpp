// SPDX-License-Identifier: BSD-3-Clause
// tests/unit/compression/codec_test.cpp -- LBG training and the window codec's round trips.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>

#include "round_to_integer.h"
#include "penumbra/compression/lbg.h"
#include "penumbra/compression/window_codec.h"
#include "penumbra/core/error.h"
#include "expect_error.h"
#include "test_fields.h"

namespace penumbra::compression {
namespace {

using testing::SyntheticField;

struct Errors {
  double max_abs = 0, psnr_db = 0;
};

Errors compare(const float* ref, const float* got, std::size_t count, double range) {
  double se = 0, mx = 0;
  for (std::size_t i = 0; i < count; ++i) {
    const double d = std::fabs(double(ref[i]) - got[i]);
    se += d * d;
    mx = std::max(mx, d);
  }
  const double mse = se / double(count);
  return {mx, mse > 0 ? 10 * std::log10(range * range / mse) : 400.0};
}

TEST(Lbg, RecoversWellSeparatedClustersAndIsDeterministic) {
  // 8 clusters in 4-D, tight around known centres: an 8-entry codebook must find them all.
  std::vector<float> centres(8 * 4), data;
  for (int c = 0; c < 8; ++c)
    for (int j = 0; j < 4; ++j) centres[c * 4 + j] = float(((c >> (j % 3)) & 1) * 10 + j);
  std::mt19937 rng(3);
  std::normal_distribution<float> noise(0.f, 0.05f);
  for (int i = 0; i < 800; ++i)
    for (int j = 0; j < 4; ++j) data.push_back(centres[(i % 8) * 4 + j] + noise(rng));
  LbgOptions o;
  o.codebook_size = 8;
  double mse = 0;
  const auto cb = train_lbg(data.data(), 800, 4, o, nullptr, &mse);
  EXPECT_LT(mse, 4 * 0.05 * 0.05 * 1.5);  // 4 dims of variance 0.0025, with 50% slack
  for (int c = 0; c < 8; ++c) {
    double best = 1e30;
    for (int e = 0; e < 8; ++e) {
      double d = 0;
      for (int j = 0; j < 4; ++j) d += std::pow(cb[e * 4 + j] - centres[c * 4 + j], 2);
      best = std::min(best, d);
    }
    EXPECT_LT(best, 0.01) << "centre " << c;
  }
  EXPECT_EQ(cb, train_lbg(data.data(), 800, 4, o));
  o.seed = 99;  // a different seed still converges to the same centres (up to order)
  EXPECT_EQ(train_lbg(data.data(), 800, 4, o).size(), cb.size());
}

TEST(Lbg, NearestSearchMatchesBruteForce) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> u(-1, 1);
  const std::uint32_t k = 37, dim = 13;
  std::vector<float> cb(k * dim), x(101 * dim);
  for (auto& c : cb) c = u(rng);
  for (auto& c : x) c = u(rng);
  NearestSearch s(cb.data(), k, dim);
  std::vector<std::uint8_t> idx(101);
  s.nearest(x.data(), 101, idx.data());
  for (int i = 0; i < 101; ++i) {
    double best = 1e30;
    int arg = -1;
    for (std::uint32_t e = 0; e < k; ++e) {
      double d = 0;
      for (std::uint32_t j = 0; j < dim; ++j) d += std::pow(double(x[i * dim + j]) - cb[e * dim + j], 2);
      if (d < best) best = d, arg = int(e);
    }
    double got = 0;
    for (std::uint32_t j = 0; j < dim; ++j) got += std::pow(double(x[i * dim + j]) - cb[idx[i] * dim + j], 2);
    EXPECT_LE(got, best + 1e-5) << "vector " << i << " best " << arg;
  }
}

TEST(Lbg, NearestSearchBreaksTiesTowardTheLowestEntry) {
  // Copies of one entry score exactly alike; the first copy wins wherever the copies fall among
  // the vector lanes and tiles of the scoring (k = 256: 16 tiles of 16 entries).
  std::mt19937 rng(2);
  std::uniform_real_distribution<float> u(-1, 1);
  const std::uint32_t k = 256, dim = 64;
  std::vector<float> cb(k * dim);
  for (auto& c : cb) c = u(rng);
  const std::uint32_t copies[][3] = {{3, 11, 200}, {17, 18, 255}, {0, 8, 16}, {100, 131, 254}};
  std::vector<float> x;
  for (const auto& c : copies) {
    for (std::uint32_t j = 0; j < dim; ++j) cb[c[1] * dim + j] = cb[c[2] * dim + j] = cb[c[0] * dim + j];
    x.insert(x.end(), cb.begin() + c[0] * dim, cb.begin() + (c[0] + 1) * dim);
  }
  NearestSearch s(cb.data(), k, dim);
  std::vector<std::uint8_t> idx(4);
  s.nearest(x.data(), 4, idx.data());
  for (int i = 0; i < 4; ++i) EXPECT_EQ(idx[i], copies[i][0]) << "vector " << i;
  std::vector<std::uint8_t> top(4 * 3);
  s.nearest_m(x.data(), 4, 3, top.data());
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 3; ++j) EXPECT_EQ(top[i * 3 + j], copies[i][j]) << "vector " << i << ", rank " << j;
}

TEST(Quantiser, RoundToIntegerIsNearbyintBelowTwoToThe51) {
  // The quantisers round by adding and subtracting 1.5 * 2^52; a flag that let the compiler
  // reassociate floating-point sums would turn that into no rounding at all.
  std::vector<double> values;
  for (int i = -4000; i <= 4000; ++i) values.push_back(i * 0.25);  // ties at every odd half
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> exponent(-20, 51), unit(0, 1);
  for (int i = 0; i < 100000; ++i) {
    const double v = std::exp2(exponent(rng)) * unit(rng);
    values.push_back(v);
    values.push_back(-v);
  }
  const double top = std::exp2(51);
  for (double v : {top - 0.5, top - 1.5, -(top - 0.5), 0.5 + std::exp2(-30), 4294967295.5, 4294967296.49})
    values.push_back(v);
  for (double v : values) ASSERT_EQ(detail::round_to_integer(v), std::nearbyint(v)) << std::hexfloat << v;
}

TEST(WindowCodec, SmoothFieldRoundTripIsAccurateAndCompact) {
  const auto f = testing::smooth_blobs(6000, 64);
  const CodecParams p;
  const auto page = encode(f, 0, 64, p);
  EXPECT_EQ(page.method, PageMethod::vq);
  std::vector<float> out(f.values.size());
  decode_window(page, out.data());
  const auto e = compare(f.values.data(), out.data(), out.size(), f.range());
  // 4 bytes per vertex and window carry the series; measured ~47 dB here, require 40.
  EXPECT_GT(e.psnr_db, 40.0);
  EXPECT_EQ(page.means.q.size() * 2 + page.vq.i8.size() + page.vq.iw.size(), 4u * f.vertices);
}

TEST(WindowCodec, StepWindowAndVertexDecodesAreBitIdentical) {
  const auto f = testing::shock_front(3000, 64);
  for (float bound : {0.f, 1e-2f * f.range()}) {
    const auto page = encode(f, 0, 64, CodecParams{}, bound);
    std::vector<float> all(f.values.size()), step(f.vertices), series(64);
    decode_window(page, all.data());
    for (std::uint32_t t : {0u, 17u, 63u}) {
      decode_step(page, t, step.data());
      EXPECT_EQ(0, std::memcmp(step.data(), all.data() + t * f.vertices, step.size() * 4)) << "step " << t;
    }
    for (std::uint64_t v : {0ull, 1234ull, 2999ull}) {
      decode_vertex(page, v, series.data());
      for (std::uint32_t t = 0; t < 64; ++t) ASSERT_EQ(series[t], all[t * f.vertices + v]) << v << "," << t;
    }
  }
}

TEST(WindowCodec, BoundHeldAtEveryValueAcrossAJumpInTime) {
  const auto f = testing::shock_front(4000, 64);
  for (double rel : {1e-2, 1e-3, 1e-5}) {
    const float bound = float(rel * f.range());
    const auto page = encode(f, 0, 64, CodecParams{}, bound);
    EXPECT_NE(page.method, PageMethod::vq);
    std::vector<float> out(f.values.size());
    decode_window(page, out.data());
    const auto e = compare(f.values.data(), out.data(), out.size(), f.range());
    EXPECT_LE(e.max_abs, bound) << "rel " << rel << " method " << to_string(page.method);
  }
}

TEST(WindowCodec, NoiseIsDetectedAsVqPoorAndCodedPredictively) {
  const auto f = testing::white_noise(3000, 64);
  const float bound = 1e-2f * f.range();
  WindowStats stats;
  const auto page = encode_window(f.values.data(), f.vertices, 64, f.times.data(), 0, CodecParams{}, bound, nullptr, &stats);
  EXPECT_EQ(page.method, PageMethod::predictive_lanes);
  EXPECT_LT(stats.predictive_bytes_estimate, stats.vq_bytes_estimate);
  EXPECT_LT(stats.sample_snr_db, 6.0);
  std::vector<float> out(f.values.size());
  decode_window(page, out.data());
  EXPECT_LE(compare(f.values.data(), out.data(), out.size(), f.range()).max_abs, bound);
  // Unbounded, noise falls back to the predictive coder at VQ's own RMS error.
  const auto unbounded = encode(f, 0, 64, CodecParams{});
  EXPECT_EQ(unbounded.method, PageMethod::predictive_lanes);
  decode_window(unbounded, out.data());
  EXPECT_LE(compare(f.values.data(), out.data(), out.size(), f.range()).max_abs, unbounded.bound);
}

TEST(WindowCodec, PartialWindowDecodesOnlyItsSteps) {
  const auto f = testing::smooth_blobs(2000, 20);
  const auto page = encode(f, 0, 20, CodecParams{});
  EXPECT_EQ(page.step_count, 20u);
  std::vector<float> out(f.values.size());
  decode_window(page, out.data());
  EXPECT_GT(compare(f.values.data(), out.data(), out.size(), f.range()).psnr_db, 40.0);
  std::vector<float> step(f.vertices);
  EXPECT_THROW(decode_step(page, 20, step.data()), Error);
}

TEST(WindowCodec, WarmStartCarriesCodebooksAndKeepsQuality) {
  const auto f = testing::smooth_blobs(4000, 128);
  WarmStart warm;
  CodecParams p;
  const auto first = encode(f, 0, 64, p, 0, &warm);
  EXPECT_EQ(warm.c8, first.vq.c8);
  const auto second = encode(f, 64, 64, p, 0, &warm);
  std::vector<float> out(f.vertices * 64);
  decode_window(second, out.data());
  EXPECT_GT(compare(f.values.data() + 64 * f.vertices, out.data(), out.size(), f.range()).psnr_db, 40.0);
  EXPECT_EQ(second.first_step, 64u);
  EXPECT_DOUBLE_EQ(second.times[0], f.times[64]);
}

TEST(WindowCodec, FixedSeedGivesIdenticalPages) {
  const auto f = testing::smooth_blobs(3000, 64);
  const auto a = encode(f, 0, 64, CodecParams{}, 1e-3f);
  const auto b = encode(f, 0, 64, CodecParams{}, 1e-3f);
  EXPECT_EQ(a.vq.c8, b.vq.c8);
  EXPECT_EQ(a.vq.cw, b.vq.cw);
  EXPECT_EQ(a.vq.i8, b.vq.i8);
  EXPECT_EQ(a.vq.iw, b.vq.iw);
  EXPECT_EQ(a.means.q, b.means.q);
  EXPECT_EQ(a.blocks.payload, b.blocks.payload);
}

TEST(WindowCodec, NonFiniteInputIsRejectedNamingStepAndVertex) {
  auto f = testing::smooth_blobs(500, 16);
  f.values[5 * 500 + 42] = std::numeric_limits<float>::quiet_NaN();
  testing::expect_error([&] { encode(f, 0, 16, CodecParams{}); }, ErrorCode::invalid_argument,
                        {"step 5, vertex 42 is NaN"}, "NaN");
  f.values[5 * 500 + 42] = std::numeric_limits<float>::infinity();
  EXPECT_THROW(encode(f, 0, 16, CodecParams{}), Error);
}

TEST(WindowCodec, BadParametersAreRejected) {
  const auto f = testing::smooth_blobs(100, 16);
  CodecParams p;
  p.window = 12;
  EXPECT_THROW(encode(f, 0, 12, p), Error);
  p = CodecParams{};
  p.codebook_size = 300;
  EXPECT_THROW(encode(f, 0, 16, p), Error);
  p = CodecParams{};
  EXPECT_THROW(encode(f, 0, 65, p), Error);
}

// Every decoder checks the shape of the page it is handed (pages from a file are checked when
// parsed; these guard pages assembled by hand), so a malformed page is an invalid_argument
// error naming the call, never a crash or a read out of bounds.
TEST(WindowCodec, MalformedPagesAreRejectedByEveryDecoder) {
  const auto f = testing::smooth_blobs(100, 16);
  CodecParams p;
  p.window = 16;
  p.codebook_size = 8;
  const EncodedPage good = encode(f, 0, 16, p);
  std::vector<float> out(f.vertices * 16);
  ASSERT_NO_THROW(decode_window(good, out.data()));
  auto expect_rejected = [&](const EncodedPage& bad, const std::string& what) {
    for (int call = 0; call < 4; ++call)
      testing::expect_error(
          [&] {
            if (call == 0) decode_window(bad, out.data());
            if (call == 1) decode_step(bad, 0, out.data());
            if (call == 2) decode_vertex(bad, 0, out.data());
            if (call == 3) StepCursor().decode(std::make_shared<const EncodedPage>(bad), 0, out.data());
          },
          ErrorCode::invalid_argument, {what}, what + ", decoder " + std::to_string(call));
  };
  EncodedPage bad = good;
  bad.window = 4;  // W / 8 would be 0: a division by zero in the decoders
  expect_rejected(bad, "window 4");
  bad = good;
  bad.step_count = 17;
  expect_rejected(bad, "step count 17");
  bad = good;
  bad.codebook_size = 300;
  expect_rejected(bad, "codebook size 300");
  bad = good;
  if (bad.method == PageMethod::vq || bad.method == PageMethod::vq_residual) {
    bad.vq.cw.pop_back();
    expect_rejected(bad, "cw holds");
  } else {
    bad.aligned.ca.pop_back();
    expect_rejected(bad, "ca holds");
  }
  bad = good;
  bad.means.q.resize(3);
  expect_rejected(bad, "mean_q holds 3");
}

// What the decoders trust without looking (they run per step, so they check only the shape):
// validate_page finds it in a page edited by hand, naming the fault and the vertex.
TEST(WindowCodec, ValidatePageFindsWhatTheDecodersTrust) {
  const auto f = testing::smooth_blobs(300, 16);
  CodecParams p;
  p.window = 16;
  p.codebook_size = 8;
  p.aligned = false;
  p.predictive_lanes = false;  // per-vertex sections (lane blocks: lane_blocks_test.cpp)
  const EncodedPage vq = encode(f, 0, 16, p);
  ASSERT_TRUE(vq.method == PageMethod::vq) << to_string(vq.method);
  const EncodedPage blocks = encode(f, 0, 16, p, 1e-4f * f.range());
  ASSERT_TRUE(blocks.method == PageMethod::vq_residual || blocks.method == PageMethod::predictive)
      << to_string(blocks.method);
  auto expect_invalid = [](const EncodedPage& bad, const std::string& what) {
    testing::expect_error([&] { validate_page(bad); }, ErrorCode::invalid_argument, {what}, what);
  };
  EXPECT_NO_THROW(validate_page(vq));
  EXPECT_NO_THROW(validate_page(blocks));
  EncodedPage bad = vq;
  bad.vq.iw[7] = 8;  // one past the codebook: the decoders would read past cw
  expect_invalid(bad, "codebook index out of range at vertex 7");
  bad = vq;
  bad.times.pop_back();
  expect_invalid(bad, "15 time values for 16 steps");
  bad = vq;
  bad.window = 4;  // the shape check runs first
  expect_invalid(bad, "window 4");
  bad = blocks;
  bad.blocks.section_bits[130] += 1;  // the second group's third vertex
  expect_invalid(bad, "section_bits does not match where the section starts at vertex 130");
  bad = blocks;
  bad.blocks.widths[2] |= 0xF;  // vertex 4 raw: 16 float32 values push every later section on
  expect_invalid(bad, "section_bits does not match where the section starts at vertex 5");
  bad = blocks;
  bad.blocks.widths[149] |= 0xF0;  // the last vertex raw: more bits than its group holds
  expect_invalid(bad, "bits of vertex 299 run past their group");
  bad = blocks;
  bad.quantiser.step = std::numeric_limits<float>::infinity();
  expect_invalid(bad, "non-finite quantisation step");
  bad = blocks;
  bad.blocks.group_offsets.back() = ~std::uint64_t(0) - 4;  // would wrap around in `back() + 8`
  expect_invalid(bad, "bit payload shorter than its groups");
  bad = blocks;
  bad.blocks.group_offsets[1] = bad.blocks.group_offsets[2] + 1;
  expect_invalid(bad, "group table is not increasing at vertex group 1");
  if (blocks.method == PageMethod::predictive) {
    bad = blocks;
    bad.quantiser.first_width = 40;
    expect_invalid(bad, "first-value width 40");
  }
  // An aligned page: a shift must fall inside the page's steps.
  CodecParams aligned = p;
  aligned.aligned = true;
  const EncodedPage shifted = encode(testing::shock_front(300, 16), 0, 16, aligned);
  ASSERT_EQ(shifted.method, PageMethod::vq_aligned) << to_string(shifted.method);
  EXPECT_NO_THROW(validate_page(shifted));
  bad = shifted;
  bad.aligned.shift[11] = 16;
  expect_invalid(bad, "aligned codebook index or shift out of range at vertex 11");
}

}  // namespace
}  // namespace penumbra::compression

namespace penumbra::compression {
namespace {

TEST(WindowCodec, IsolatedOutliersArePatchedAndStayRandomlyAccessible) {
  // A smooth field plus one large spike per vertex at a vertex-dependent step: the residual
  // blocks should store the spike as an exception (code 14) rather than widen all 64 values.
  auto f = testing::smooth_blobs(2000, 64);
  const float spike = 0.5f * f.range();
  for (std::uint64_t v = 0; v < f.vertices; ++v) f.values[(v * 7 % 64) * f.vertices + v] += spike;
  const float bound = 1e-2f * f.range();
  CodecParams sections;
  sections.predictive_lanes = false;
  const auto page = encode(f, 0, 64, sections, bound);
  ASSERT_TRUE(page.method == PageMethod::vq_residual || page.method == PageMethod::vq_aligned_residual ||
              page.method == PageMethod::predictive)
      << to_string(page.method);
  std::size_t patched = 0;
  for (std::uint64_t v = 0; v < f.vertices; ++v) patched += page.blocks.width(v) == 14;
  EXPECT_GT(patched, f.vertices / 2) << to_string(page.method);
  std::vector<float> all(f.values.size()), one(64), step(f.vertices);
  decode_window(page, all.data());
  EXPECT_LE(compare(f.values.data(), all.data(), all.size(), f.range()).max_abs, bound);
  for (std::uint64_t v : {0ull, 9ull, 1999ull}) {
    decode_vertex(page, v, one.data());
    for (std::uint32_t t = 0; t < 64; ++t) ASSERT_EQ(one[t], all[t * f.vertices + v]);
  }
  for (std::uint32_t t : {0u, 7u, 63u}) {
    decode_step(page, t, step.data());
    ASSERT_EQ(0, std::memcmp(step.data(), all.data() + t * f.vertices, step.size() * 4));
  }
  EXPECT_GT(page.vq_bytes_estimate, 0.f);
  EXPECT_GT(page.predictive_bytes_estimate, 0.f);
}

}  // namespace
}  // namespace penumbra::compression

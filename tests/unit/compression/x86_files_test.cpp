// SPDX-License-Identifier: BSD-3-Clause
// tests/unit/compression/x86_files_test.cpp -- files an x86-64 build wrote, one per page method
// with codebooks or bit sections, read bit for bit as that build read them, by every decoder of
// this build: the vector ones on x86-64, the scalar ones everywhere else (scripts/cross_aarch64.sh
// runs this on aarch64). Lane-block pages have files of their own (lane_blocks_test.cpp).
//
// data/x86_*.pnbf and the CRC-32 of every step their build decoded (data/x86_files.crc32: the
// decoded steps themselves would take 1 MB) are written by this test on x86-64 when
// PNB_WRITE_X86_FILES names a folder:
//   PNB_WRITE_X86_FILES=tests/unit/compression/data \
//     build/tests/unit/compression/penumbra_compression_tests --gtest_filter='X86Files.*'
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "crc32_reference.h"
#include "lane_blocks.h"
#include "penumbra/compression/field_file.h"
#include "penumbra/compression/window_codec.h"
#include "stream_field.h"
#include "temp_path.h"
#include "test_fields.h"

namespace penumbra::compression {
namespace {

using testing::SyntheticField;

constexpr std::uint32_t kSteps = 64;  // one page, a window the x86-64 decoders' fastest paths take

struct Case {
  const char* name;
  PageMethod method;
  SyntheticField field;
  CodecParams codec;
};

// 1001 vertices where codebooks must pay for themselves (125 blocks of 8 lanes and a scalar tail,
// 62 blocks of 16 and a partial one); 61 for the predictive sections of white noise.
std::vector<Case> cases() {
  CodecParams plain = testing::small_plain_codebooks(), aligned = testing::small_aligned_codebooks();
  plain.predictive_lanes = aligned.predictive_lanes = false;
  CodecParams plain_bounded = plain, aligned_bounded = aligned, sections;
  plain_bounded.bound = {BoundKind::range_relative, 3e-2};
  aligned_bounded.codebook_size = 16;
  aligned_bounded.bound = sections.bound = {BoundKind::range_relative, 1e-2};
  sections.predictive_lanes = false;
  auto waves = testing::oscillating_sources(1001, kSteps);
  auto noise = testing::white_noise(61, kSteps);
  testing::add_outliers(waves);
  testing::add_outliers(noise);
  return {{"x86_vq", PageMethod::vq, testing::oscillating_sources(1001, kSteps), plain},
          {"x86_vq_residual", PageMethod::vq_residual, waves, plain_bounded},
          {"x86_vq_aligned", PageMethod::vq_aligned, testing::relaxing_front(1001, kSteps), aligned},
          {"x86_vq_aligned_residual", PageMethod::vq_aligned_residual, testing::relaxing_front(1001, kSteps),
           aligned_bounded},
          {"x86_predictive", PageMethod::predictive, noise, sections}};
}

// Restores the defaults (vector decoders on, the widest the CPU has) whatever the test does.
struct VectorDecodeGuard {
  ~VectorDecodeGuard() {
    set_vector_decode(true);
    detail::cap_lane_isa(detail::LaneIsa::avx512_vbmi2);
  }
};

std::uint32_t step_crc(const float* step, std::uint64_t vertices) {
  return testing::crc32_reference(step, vertices * sizeof(float));
}

// Every step of a field, from read_step.
std::vector<float> read_steps(const CompressedField& field, std::uint64_t vertices) {
  std::vector<float> out(field.step_count() * vertices);
  for (std::uint64_t t = 0; t < field.step_count(); ++t) field.read_step(t, out.data() + t * vertices);
  return out;
}

// The CRC-32 of each case's decoded steps, from data/x86_files.crc32 ("NAME STEP CRC" lines).
std::map<std::string, std::vector<std::uint32_t>> read_crcs(const std::string& path) {
  std::map<std::string, std::vector<std::uint32_t>> crcs;
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream fields(line);
    std::string name;
    std::uint32_t step = 0, crc = 0;
    fields >> name >> step >> std::hex >> crc;
    auto& list = crcs[name];
    if (list.size() == step) list.push_back(crc);
  }
  return crcs;
}

// Writes each case's file and the CRC-32 of the steps this build decodes from it (x86-64 only:
// the files stand for what an x86-64 build writes).
void write_cases(const std::string& dir) {
  std::ofstream crcs(dir + "/x86_files.crc32", std::ios::trunc);
  crcs << "# CRC-32 of each step an x86-64 build decoded from x86_NAME.pnbf (tests/unit/compression/"
          "x86_files_test.cpp)\n";
  for (const Case& c : cases()) {
    const std::string path = dir + "/" + c.name + ".pnbf";
    testing::stream_field(c.field, path, c.codec, "f");
    const auto decoded = read_steps(*CompressedField::open(path), c.field.vertices);
    for (std::uint32_t t = 0; t < kSteps; ++t)
      crcs << c.name << ' ' << t << ' ' << std::hex << step_crc(decoded.data() + t * c.field.vertices, c.field.vertices)
           << std::dec << '\n';
  }
}

TEST(X86Files, ReadBitForBitAsTheBuildThatWroteThemReadThem) {
  VectorDecodeGuard guard;
  const std::string dir = PNB_COMPRESSION_TEST_DATA;
  if (const char* out = std::getenv("PNB_WRITE_X86_FILES")) {
#if defined(__x86_64__)
    write_cases(out);
    GTEST_SKIP() << "wrote the files to " << out << " instead of reading them";
#else
    FAIL() << "PNB_WRITE_X86_FILES: the files must be written by an x86-64 build";
#endif
  }
  const auto crcs = read_crcs(dir + "/x86_files.crc32");
  for (const Case& c : cases()) {
    const std::uint64_t N = c.field.vertices;
    const auto field = CompressedField::open(dir + "/" + c.name + ".pnbf");
    field->verify();
    ASSERT_EQ(field->step_count(), kSteps) << c.name;
    ASSERT_EQ(field->page_count(), 1u) << c.name;
    const auto page = field->load_page(0);
    ASSERT_EQ(page->method, c.method) << c.name << ": " << to_string(page->method);
    ASSERT_TRUE(crcs.count(c.name)) << c.name;
    const std::vector<std::uint32_t>& expected = crcs.at(c.name);
    ASSERT_EQ(expected.size(), kSteps) << c.name;
    // The widest vector decoders this CPU has, the AVX2 ones, the scalar ones, each set once
    // (off x86-64 only the scalar ones): window, step and cursor decodes give the x86-64 build's bits.
    std::vector<float> window(N * kSteps), step(N);
    std::set<std::pair<bool, detail::LaneIsa>> decoders_run;
    for (const auto isa : {detail::LaneIsa::avx512_vbmi2, detail::LaneIsa::avx2, detail::LaneIsa::scalar}) {
      set_vector_decode(isa != detail::LaneIsa::scalar);
      detail::cap_lane_isa(isa);
      if (!decoders_run.insert({vector_decode_active(), detail::lane_isa()}).second) continue;
      const std::string with = std::string(c.name) + ", decoders up to " + std::to_string(int(isa));
      const auto steps = read_steps(*field, N);
      decode_window(*page, window.data());
      StepCursor cursor;
      for (std::uint32_t t = 0; t < kSteps; ++t) {
        ASSERT_EQ(step_crc(steps.data() + t * N, N), expected[t]) << with << ": read_step " << t;
        ASSERT_EQ(step_crc(window.data() + t * N, N), expected[t]) << with << ": decode_window, step " << t;
        decode_step(*page, t, step.data());
        ASSERT_EQ(step_crc(step.data(), N), expected[t]) << with << ": decode_step " << t;
        cursor.decode(page, t, step.data());
        ASSERT_EQ(step_crc(step.data(), N), expected[t]) << with << ": cursor, step " << t;
      }
      // Within the bound of the source regenerated here (whose libm may round differently from
      // the x86-64 build's: a margin of 1e-6 of the range), where the case has one.
      if (c.codec.bound.kind == BoundKind::range_relative) {
        const double bound = c.codec.bound.value * c.field.range() * (1 + 1e-6);
        for (std::size_t i = 0; i < steps.size(); ++i)
          ASSERT_LE(std::fabs(double(steps[i]) - c.field.values[i]), bound) << with << ": value " << i;
      }
    }
  }
}

}  // namespace
}  // namespace penumbra::compression

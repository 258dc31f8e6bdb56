// SPDX-License-Identifier: BSD-3-Clause
// tests/fuzz/coordinate_log_fuzz.cpp -- the store's exact coordinate log (exact.pnbc) reader
// (ExactCoordinateReader), as StoredRun opens it for a moving mesh: the header against the point
// count the header itself names and against another, then every record. Each input is read as it
// is and again with its first record's FNV-1a checksum made right, so that mutations reach the
// coordinates' read.
#include <cstdint>
#include <vector>

#include "exact_coordinates.h"
#include "fuzz_util.h"
#include "penumbra/core/error.h"

namespace {

constexpr std::size_t kHeader = 24;  // magic, version, reserved, point count

void read(const std::vector<std::uint8_t>& bytes, std::uint64_t points) {
  using penumbra::Error;
  const std::string path = penumbra::fuzz::temp_dir() + "/exact.pnbc";
  penumbra::fuzz::write_file(path, bytes.data(), bytes.size());
  try {
    const penumbra::insitu::ExactCoordinateReader reader(path, points);
    std::vector<double> xyz;
    for (std::size_t r = 0; r < reader.times().size(); ++r) {
      try {
        reader.read(r, xyz);
      } catch (const Error& e) {
        penumbra::fuzz::expect_code(e, penumbra::ErrorCode::io_error, "ExactCoordinateReader::read");
        continue;
      }
      if (xyz.size() != 3 * points) penumbra::fuzz::fail("ExactCoordinateReader::read returned the wrong count");
    }
  } catch (const Error& e) {
    penumbra::fuzz::expect_code(e, penumbra::ErrorCode::io_error, "ExactCoordinateReader");
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::vector<std::uint8_t> bytes(data, data + size);
  // The point count the header names, bounded so that a record fits the input; and one more.
  std::uint64_t points = size >= kHeader ? penumbra::fuzz::load<std::uint64_t>(bytes, 16) : 1;
  if (points > size / 24) points = 1;
  read(bytes, points);
  read(bytes, points + 1);
  const std::size_t record = 8 + 24 * points + 8;
  if (size >= kHeader + record) {
    std::uint64_t h = 1469598103934665603ull;
    for (std::size_t i = kHeader; i < kHeader + record - 8; ++i) h = (h ^ bytes[i]) * 1099511628211ull;
    if (penumbra::fuzz::load<std::uint64_t>(bytes, kHeader + record - 8) != h) {
      penumbra::fuzz::store(bytes, kHeader + record - 8, h);
      read(bytes, points);
    }
  }
  return 0;
}

// SPDX-License-Identifier: BSD-3-Clause
// tests/fuzz/cinema_csv_fuzz.cpp -- the Cinema database's data.csv reader that resume uses
// (CinemaDatabase::parse_csv, RFC 4180 quoting): any text gives a table whose rows all have the
// header's width, or an Error naming the line.
#include <cstdint>
#include <string>

#include "cinema_database.h"
#include "fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const auto table = penumbra::insitu::CinemaDatabase::parse_csv(text, "'data.csv'");
    for (const auto& row : table)
      if (row.empty() || row.size() != table.front().size()) penumbra::fuzz::fail("parse_csv returned a ragged table");
  } catch (const penumbra::Error& e) {
    penumbra::fuzz::expect_code(e, penumbra::ErrorCode::invalid_argument, "parse_csv");
  }
  return 0;
}

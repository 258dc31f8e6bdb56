// SPDX-License-Identifier: BSD-3-Clause
// tests/fuzz/cinema_csv_fuzz.cpp -- the Cinema database's data.csv reader that resume uses
// (CinemaDatabase::parse_csv, RFC 4180 quoting): any text gives a table whose rows all have the
// header's width, or an Error naming the line.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "cinema_database.h"
#include "penumbra/core/error.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const auto table = penumbra::insitu::CinemaDatabase::parse_csv(text, "'data.csv'");
    for (const auto& row : table)
      if (row.empty() || row.size() != table.front().size()) {
        std::fprintf(stderr, "parse_csv returned a ragged table\n");
        std::abort();
      }
  } catch (const penumbra::Error& e) {
    if (e.code() != penumbra::ErrorCode::invalid_argument) {
      std::fprintf(stderr, "parse_csv: unexpected error code: %s\n", e.what());
      std::abort();
    }
  }
  return 0;
}

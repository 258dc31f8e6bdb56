// SPDX-License-Identifier: BSD-3-Clause
// tests/unit/insitu/database_checks.h -- what a Cinema database left by the helper solver
// (kill_helper.cpp: 32x32 images) must be, whatever stopped it
#pragma once
#include <gtest/gtest.h>

#include <filesystem>
#include <set>
#include <string>
#include <vector>

#include "cinema_database.h"
#include "penumbra/render/image.h"
#include "test_util.h"

namespace penumbra::insitu::testing {

/// Every row's FILE exists and decodes as a 32x32 PNG, and no two rows share their parameters;
/// returns the rows (header first).
inline std::vector<std::vector<std::string>> check_valid_database(const std::string& dir) {
  const auto table = CinemaDatabase::parse_csv(read_text(dir + "/data.csv"), "data.csv");
  EXPECT_FALSE(table.empty());
  if (table.empty()) return table;
  EXPECT_EQ(table.at(0), (std::vector<std::string>{"time", "phi", "theta", "field", "FILE"}));
  std::set<std::vector<std::string>> keys;
  for (std::size_t r = 1; r < table.size(); ++r) {
    int w = 0, h = 0;
    EXPECT_NO_THROW(render::read_png_rgb(dir + "/" + table[r].back(), w, h)) << table[r].back();
    EXPECT_EQ(w, 32);
    EXPECT_EQ(h, 32);
    EXPECT_TRUE(keys.insert({table[r].begin(), table[r].end() - 1}).second) << "duplicate parameters in row " << r;
  }
  return table;
}

/// No temporary file of an atomic write is left anywhere under `dir`.
inline void expect_no_temporaries(const std::string& dir) {
  for (const auto& e : std::filesystem::recursive_directory_iterator(dir))
    EXPECT_EQ(e.path().lexically_relative(dir).string().find(".tmp"), std::string::npos) << "left over: " << e.path();
}

}  // namespace penumbra::insitu::testing

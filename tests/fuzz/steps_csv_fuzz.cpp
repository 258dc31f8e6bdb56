// SPDX-License-Identifier: BSD-3-Clause
// tests/fuzz/steps_csv_fuzz.cpp -- a store segment's steps.csv reader (parse_steps_csv, which
// StoredRun::open calls on the file): (cycle, finite time) per line, or an Error naming the line.
#include <cmath>
#include <cstdint>
#include <sstream>
#include <string>

#include "fuzz_util.h"
#include "steps_csv.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
  try {
    for (const auto& [cycle, time] : penumbra::insitu::parse_steps_csv(in, "steps.csv"))
      if (!std::isfinite(time))
        penumbra::fuzz::fail("parse_steps_csv returned a time that is not finite (cycle " + std::to_string(cycle) + ")");
  } catch (const penumbra::Error& e) {
    penumbra::fuzz::expect_code(e, penumbra::ErrorCode::io_error, "parse_steps_csv");
  }
  return 0;
}

// SPDX-License-Identifier: BSD-3-Clause
// tests/fuzz/steps_csv_fuzz.cpp -- a store segment's steps.csv reader (parse_steps_csv, which
// StoredRun::open calls on the file): (cycle, finite time) per line, or an Error naming the line.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>

#include "penumbra/core/error.h"
#include "steps_csv.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
  try {
    for (const auto& [cycle, time] : penumbra::insitu::parse_steps_csv(in, "steps.csv"))
      if (!std::isfinite(time)) {
        std::fprintf(stderr, "parse_steps_csv returned a time that is not finite (cycle %lld)\n",
                     static_cast<long long>(cycle));
        std::abort();
      }
  } catch (const penumbra::Error& e) {
    if (e.code() != penumbra::ErrorCode::io_error) {
      std::fprintf(stderr, "parse_steps_csv: unexpected error code: %s\n", e.what());
      std::abort();
    }
  }
  return 0;
}

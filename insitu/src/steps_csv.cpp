// SPDX-License-Identifier: BSD-3-Clause
// insitu/src/steps_csv.cpp -- the store's step lists
#include "steps_csv.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "penumbra/core/error.h"

namespace penumbra::insitu {

std::vector<std::pair<std::int64_t, double>> parse_steps_csv(std::istream& in, const std::string& source) {
  std::vector<std::pair<std::int64_t, double>> steps;
  std::string line;
  std::getline(in, line);
  for (int row = 2; std::getline(in, line); ++row) {
    long long cycle = 0;
    double time = 0;
    char comma = 0;
    std::istringstream ls(line);
    if (!(ls >> cycle >> comma >> time) || comma != ',' || !std::isfinite(time))
      throw Error(ErrorCode::io_error, source + " line " + std::to_string(row) + " is not 'cycle,time'");
    steps.emplace_back(cycle, time);
  }
  return steps;
}

std::int64_t index_of_time(const std::vector<double>& times, double time) {
  const auto pos = std::find(times.begin(), times.end(), time);
  return pos == times.end() ? -1 : static_cast<std::int64_t>(pos - times.begin());
}

void write_steps_csv(const std::string& path, const std::vector<std::pair<std::int64_t, double>>& steps) {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp, std::ios::trunc);
    out << "cycle,time\n";
    char line[64];
    for (const auto& [cycle, time] : steps) {
      std::snprintf(line, sizeof line, "%lld,%.17g\n", static_cast<long long>(cycle), time);
      out << line;
    }
    out.flush();
    if (!out) throw Error(ErrorCode::io_error, "store: cannot write '" + tmp + "' (disk full?)");
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) throw Error(ErrorCode::io_error, "store: cannot rename '" + tmp + "': " + ec.message());
}

}  // namespace penumbra::insitu

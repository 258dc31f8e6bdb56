// SPDX-License-Identifier: BSD-3-Clause
// insitu/src/steps_csv.h -- the store's step lists (steps.csv), written and read back
#pragma once
#include <cstdint>
#include <istream>
#include <string>
#include <utility>
#include <vector>

namespace penumbra::insitu {

/// Reads a store segment's `steps.csv` (FieldStore writes it: a header line, then one
/// `cycle,time` line per recorded step) from `in`: (cycle, time) per line after the header.
/// Throws Error(io_error) naming `source` and the line that is not `cycle,time` with an integer
/// cycle and a finite time.
std::vector<std::pair<std::int64_t, double>> parse_steps_csv(std::istream& in, const std::string& source);

/// The index of `time` in `times` (a stored file's step times), or -1 when it has no step then:
/// how a stored field, or a moving mesh's coordinates, is looked up at a step of the run.
std::int64_t index_of_time(const std::vector<double>& times, double time);

/// Writes `steps` to `path` in that form, whole, through a temporary file renamed into place, so
/// that a reader never sees a half-written list. Throws Error(io_error) naming the file.
void write_steps_csv(const std::string& path, const std::vector<std::pair<std::int64_t, double>>& steps);

}  // namespace penumbra::insitu

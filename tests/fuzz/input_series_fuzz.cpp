// SPDX-License-Identifier: BSD-3-Clause
// tests/fuzz/input_series_fuzz.cpp -- penumbra-replay's step lists: the ParaView `.series` JSON
// index and the `.pvd` XML collection, read by InputSeries::open (which lists their steps and
// checks that each listed file exists; it reads no grid, so VTK's grid readers are not fuzzed).
// Text whose first non-blank character is '<' is written as `list.pvd`, anything else as
// `list.series`, in a folder that also holds `a.vtk`, `b.vtu` and `c.vtk` for them to list.
#include <cstdint>
#include <memory>
#include <string>

#include "fuzz_util.h"
#include "input_series.h"
#include "penumbra/core/error.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string dir = [] {
    const std::string d = penumbra::fuzz::temp_dir();
    for (const char* part : {"a.vtk", "b.vtu", "c.vtk"}) penumbra::fuzz::write_file(d + "/" + part, "", 0);
    return d;
  }();
  const std::string text(reinterpret_cast<const char*>(data), size);
  const std::size_t first = text.find_first_not_of(" \t\n\v\f\r");
  const std::string path = dir + (first != std::string::npos && text[first] == '<' ? "/list.pvd" : "/list.series");
  penumbra::fuzz::write_file(path, data, size);
  try {
    const auto series = penumbra::replay::InputSeries::open(path);
    if (series->size() < 1) penumbra::fuzz::fail("InputSeries::open gave a series without steps");
    (void)series->describe();
  } catch (const penumbra::Error&) {
  }
  return 0;
}

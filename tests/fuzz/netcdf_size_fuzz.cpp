// SPDX-License-Identifier: BSD-3-Clause
// tests/fuzz/netcdf_size_fuzz.cpp -- penumbra-replay's own netCDF header walk
// (netcdf_classic_min_size, which tells a truncated Exodus II file before VTK reads it): any
// bytes give a size or "not classic netCDF", in time proportional to the header.
#include <cstdint>
#include <sstream>
#include <string>

#include "netcdf_size.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
  (void)penumbra::replay::netcdf_classic_min_size(in);
  return 0;
}

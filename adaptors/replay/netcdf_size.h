// SPDX-License-Identifier: BSD-3-Clause
// adaptors/replay/netcdf_size.h -- detects truncated classic netCDF (Exodus II) files
#pragma once
#include <cstdint>
#include <istream>
#include <optional>
#include <string>

namespace penumbra::replay {

/// The smallest byte size a complete classic (CDF-1) or 64-bit-offset (CDF-2) netCDF file with
/// this header can have; nullopt for other formats (CDF-5, HDF5-based netCDF-4) or an unreadable
/// header. A smaller file on disk was cut off.
std::optional<std::uint64_t> netcdf_classic_min_size(const std::string& path);
/// The same for a file's bytes read from `in`, from its first byte.
std::optional<std::uint64_t> netcdf_classic_min_size(std::istream& in);

}  // namespace penumbra::replay

// SPDX-License-Identifier: BSD-3-Clause
// adaptors/replay/netcdf_size.cpp -- the size a classic netCDF file must have, from its header
//
// netCDF reads records past the end of a truncated file as zeros without reporting anything,
// so a cut-off Exodus file would replay as silent zero fields. The classic header (CDF-1 and
// CDF-2, the formats Exodus writes by default) says where every variable starts and how big it
// is, which gives the smallest size a complete file can have.
#include "netcdf_size.h"

#include <cstdint>
#include <fstream>
#include <vector>

namespace penumbra::replay {
namespace {

class HeaderReader {
public:
  HeaderReader(std::istream& in, bool offsets64) : m_in(in), m_offsets64(offsets64) {}
  bool ok() const { return static_cast<bool>(m_in); }
  std::uint64_t u32() {
    unsigned char b[4] = {};
    m_in.read(reinterpret_cast<char*>(b), 4);
    return (std::uint64_t{b[0]} << 24) | (std::uint64_t{b[1]} << 16) | (std::uint64_t{b[2]} << 8) | b[3];
  }
  std::uint64_t offset() {
    const std::uint64_t first = u32();  // the high word of a 64-bit offset: read before the low one
    return m_offsets64 ? (first << 32) | u32() : first;
  }
  void skip(std::uint64_t bytes) { m_in.seekg(static_cast<std::streamoff>((bytes + 3) / 4 * 4), std::ios::cur); }
  void skip_name() { skip(u32()); }
  void skip_attributes() {
    const std::uint64_t tag = u32(), count = u32();
    if (tag == 0) return;  // ABSENT
    for (std::uint64_t i = 0; i < count && ok(); ++i) {
      skip_name();
      const std::uint64_t type = u32(), n = u32();
      skip(n * type_size(type));
    }
  }
  static std::uint64_t type_size(std::uint64_t type) {
    switch (type) {
      case 1: case 2: return 1;
      case 3: return 2;
      case 4: case 5: return 4;
      case 6: return 8;
      default: return 0;
    }
  }

private:
  std::istream& m_in;
  bool m_offsets64;
};

}  // namespace

std::optional<std::uint64_t> netcdf_classic_min_size(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return netcdf_classic_min_size(in);
}

std::optional<std::uint64_t> netcdf_classic_min_size(std::istream& in) {
  char magic[4] = {};
  in.read(magic, 4);
  if (!in || magic[0] != 'C' || magic[1] != 'D' || magic[2] != 'F' || (magic[3] != 1 && magic[3] != 2))
    return std::nullopt;
  HeaderReader h(in, magic[3] == 2);
  const std::uint64_t numrecs = h.u32();
  if (numrecs == 0xFFFFFFFFu) return std::nullopt;  // streaming: record count not known

  std::vector<std::uint64_t> dim_lengths;
  if (h.u32() != 0) {
    const std::uint64_t n = h.u32();
    for (std::uint64_t i = 0; i < n && h.ok(); ++i) {
      h.skip_name();
      dim_lengths.push_back(h.u32());
    }
  } else {
    h.u32();
  }
  h.skip_attributes();

  struct Var { std::uint64_t vsize, begin; bool record; };
  std::vector<Var> vars;
  if (h.u32() != 0) {
    const std::uint64_t n = h.u32();
    for (std::uint64_t i = 0; i < n && h.ok(); ++i) {
      h.skip_name();
      const std::uint64_t ndims = h.u32();
      bool record = false;
      for (std::uint64_t d = 0; d < ndims && h.ok(); ++d) {  // ndims is the file's word: up to 2^32 - 1
        const std::uint64_t id = h.u32();
        if (d == 0 && id < dim_lengths.size() && dim_lengths[id] == 0) record = true;
      }
      h.skip_attributes();
      h.u32();  // nc_type
      const std::uint64_t vsize = h.u32();
      vars.push_back({vsize, h.offset(), record});
    }
  }
  if (!h.ok()) return std::nullopt;

  std::uint64_t record_size = 0;
  for (const Var& v : vars) record_size += v.record ? v.vsize : 0;
  std::uint64_t needed = 0;
  for (const Var& v : vars) {
    std::uint64_t end = v.begin + v.vsize;
    if (v.record) end = numrecs == 0 ? v.begin : v.begin + (numrecs - 1) * record_size + v.vsize;
    needed = std::max(needed, end);
  }
  // The last variable's padding (at most 3 bytes) need not be on disk.
  return needed > 3 ? needed - 3 : needed;
}

}  // namespace penumbra::replay

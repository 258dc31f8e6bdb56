// SPDX-License-Identifier: BSD-3-Clause
// insitu/src/stored_mesh.cpp -- the store's mesh file
#include "stored_mesh.h"

#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "checksum.h"
#include "penumbra/core/error.h"

namespace penumbra::insitu {
namespace {

constexpr char kMagic[8] = {'P', 'N', 'B', 'M', 'E', 'S', 'H', '1'};

template <class T>
void put(std::vector<unsigned char>& out, const T* data, std::size_t n) {
  const auto* b = reinterpret_cast<const unsigned char*>(data);
  out.insert(out.end(), b, b + n * sizeof(T));
}

[[noreturn]] void bad(const std::string& path, const std::string& what) {
  throw Error(ErrorCode::io_error, "stored mesh '" + path + "': " + what);
}

}  // namespace

MeshView StoredMesh::view() const {
  MeshView v;
  v.points = {reinterpret_cast<const std::byte*>(xyz.data()), xyz.size() / 3, 3 * sizeof(double)};
  v.point_type = ScalarType::float64;
  v.connectivity = {connectivity.data(), connectivity.size(), ScalarType::int64};
  v.offsets = {offsets.data(), offsets.size(), ScalarType::int64};
  v.cell_types = types.data();
  v.cell_type_count = types.size();
  v.topology_version = 1;
  return v;
}

StoredMesh copy_mesh(const MeshView& mesh) {
  StoredMesh m;
  const std::size_t np = mesh.point_count(), nc = mesh.cell_count();
  m.xyz.reserve(3 * np);
  for (std::size_t i = 0; i < np; ++i) {
    const Vec3d p = mesh.point(i);
    m.xyz.insert(m.xyz.end(), {p.x, p.y, p.z});
  }
  m.offsets.resize(nc + 1);
  m.types.resize(nc);
  for (std::size_t c = 0; c < nc; ++c) {
    m.offsets[c] = mesh.cell_begin(c);
    m.types[c] = mesh.cell_type(c);
  }
  m.offsets[nc] = static_cast<std::int64_t>(mesh.connectivity.count);
  m.connectivity.resize(mesh.connectivity.count);
  for (std::size_t i = 0; i < mesh.connectivity.count; ++i) m.connectivity[i] = mesh.connectivity[i];
  return m;
}

void write_stored_mesh(const std::string& path, const StoredMesh& mesh) {
  std::vector<unsigned char> bytes(kMagic, kMagic + 8);
  const std::uint64_t counts[3] = {mesh.xyz.size() / 3, mesh.types.size(), mesh.connectivity.size()};
  put(bytes, counts, 3);
  put(bytes, mesh.xyz.data(), mesh.xyz.size());
  put(bytes, mesh.offsets.data(), mesh.offsets.size());
  put(bytes, mesh.connectivity.data(), mesh.connectivity.size());
  put(bytes, mesh.types.data(), mesh.types.size());
  const std::uint64_t sum = fnv1a(bytes.data(), bytes.size());
  put(bytes, &sum, 1);
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
    out.flush();
    if (!out) {
      std::error_code ec;
      std::filesystem::remove(tmp, ec);
      throw Error(ErrorCode::io_error, "stored mesh '" + path + "': cannot write (disk full or not writable)");
    }
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) throw Error(ErrorCode::io_error, "stored mesh '" + path + "': cannot rename into place: " + ec.message());
}

StoredMesh read_stored_mesh(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) bad(path, "cannot be opened");
  const std::vector<unsigned char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return parse_stored_mesh(bytes.data(), bytes.size(), path);
}

StoredMesh parse_stored_mesh(const unsigned char* bytes, std::size_t size, const std::string& path) {
  if (size < 8 + 24 + 8 || std::memcmp(bytes, kMagic, 8) != 0)
    bad(path, "is not a Penumbra mesh file (or is truncated before its header ends)");
  std::uint64_t counts[3];
  std::memcpy(counts, bytes + 8, sizeof counts);
  const std::uint64_t np = counts[0], nc = counts[1], nconn = counts[2];
  // Counts bounded by the file size before any multiplication can overflow.
  if (np > size || nc > size || nconn > size) bad(path, "has impossible counts");
  const std::uint64_t need = 8 + 24 + np * 24 + (nc + 1) * 8 + nconn * 8 + nc + 8;
  if (size != need)
    bad(path, "has " + std::to_string(size) + " bytes, expected " + std::to_string(need) + " (truncated?)");
  std::uint64_t sum = 0;
  std::memcpy(&sum, bytes + need - 8, 8);
  if (sum != fnv1a(bytes, need - 8)) bad(path, "checksum mismatch (corrupt file)");
  StoredMesh m;
  const unsigned char* p = bytes + 32;
  auto take = [&p](auto& vec, std::size_t n) {
    vec.resize(n);
    if (n > 0) std::memcpy(vec.data(), p, n * sizeof(vec[0]));  // an empty vector's data() may be null
    p += n * sizeof(vec[0]);
  };
  take(m.xyz, 3 * np);
  take(m.offsets, nc + 1);
  take(m.connectivity, nconn);
  take(m.types, nc);
  if (m.offsets.front() != 0 || m.offsets.back() != static_cast<std::int64_t>(nconn))
    bad(path, "has offsets inconsistent with its connectivity");
  return m;
}

}  // namespace penumbra::insitu

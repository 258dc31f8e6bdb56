// SPDX-License-Identifier: BSD-3-Clause
// insitu/src/exact_coordinates.cpp -- the exact coordinate log of a moving mesh
#include "exact_coordinates.h"

#include <cstring>
#include <fstream>
#include <unistd.h>

#include "checksum.h"
#include "penumbra/core/error.h"

namespace penumbra::insitu {
namespace {

constexpr char kMagic[8] = {'P', 'N', 'B', 'C', 'O', 'O', 'R', 'D'};
constexpr std::uint32_t kVersion = 1;
constexpr std::size_t kHeaderBytes = 8 + 4 + 4 + 8;  // magic, version, reserved, point count

std::size_t record_bytes(std::uint64_t points) { return 8 + 24 * points + 8; }

[[noreturn]] void bad(const std::string& path, const std::string& what) {
  throw Error(ErrorCode::io_error, "coordinates '" + path + "': " + what);
}

}  // namespace

ExactCoordinateWriter::ExactCoordinateWriter(std::string path, std::uint64_t point_count)
    : m_path(std::move(path)), m_points(point_count) {
  m_file = std::fopen(m_path.c_str(), "wb");
  if (!m_file) bad(m_path, "cannot be created");
  unsigned char header[kHeaderBytes] = {};
  std::memcpy(header, kMagic, 8);
  std::memcpy(header + 8, &kVersion, 4);
  std::memcpy(header + 16, &m_points, 8);
  if (std::fwrite(header, 1, sizeof header, m_file) != sizeof header || std::fflush(m_file) != 0) {
    std::fclose(m_file);
    m_file = nullptr;
    bad(m_path, "cannot be written (disk full?)");
  }
  m_size = static_cast<long>(sizeof header);
}

ExactCoordinateWriter::~ExactCoordinateWriter() {
  if (m_file) std::fclose(m_file);
}

void ExactCoordinateWriter::append(double time, const std::vector<Vec3d>& points) {
  require(points.size() == m_points, "coordinates '" + m_path + "': " + std::to_string(points.size()) +
                                         " points for a log of " + std::to_string(m_points));
  std::vector<unsigned char> record(record_bytes(m_points));
  std::memcpy(record.data(), &time, 8);
  if (m_points > 0) std::memcpy(record.data() + 8, points.data(), 24 * m_points);  // Vec3d is three packed doubles
  const std::uint64_t sum = fnv1a(record.data(), record.size() - 8);
  std::memcpy(record.data() + record.size() - 8, &sum, 8);
  if (std::fwrite(record.data(), 1, record.size(), m_file) != record.size() || std::fflush(m_file) != 0) {
    // A torn record would misalign every later one: cut the file back to the last whole record.
    std::clearerr(m_file);
    if (ftruncate(fileno(m_file), m_size) != 0 || std::fseek(m_file, m_size, SEEK_SET) != 0)
      bad(m_path, "a record could not be written, nor the file cut back to the records before it");
    bad(m_path, "cannot append the coordinates at time " + std::to_string(time) + " (disk full?)");
  }
  m_size += static_cast<long>(record.size());
}

ExactCoordinateReader::ExactCoordinateReader(std::string path, std::uint64_t point_count)
    : m_path(std::move(path)), m_points(point_count) {
  std::ifstream in(m_path, std::ios::binary | std::ios::ate);
  if (!in) bad(m_path, "cannot be opened");
  const auto size = static_cast<std::uint64_t>(in.tellg());
  unsigned char header[kHeaderBytes];
  in.seekg(0);
  if (size < kHeaderBytes || !in.read(reinterpret_cast<char*>(header), kHeaderBytes) || std::memcmp(header, kMagic, 8) != 0)
    bad(m_path, "is not a Penumbra coordinate log");
  std::uint32_t version = 0;
  std::uint64_t points = 0;
  std::memcpy(&version, header + 8, 4);
  std::memcpy(&points, header + 16, 8);
  if (version != kVersion) bad(m_path, "has format version " + std::to_string(version) + "; this build reads version 1");
  if (points != m_points)
    bad(m_path, "holds " + std::to_string(points) + " points per step; the mesh has " + std::to_string(m_points));
  const std::uint64_t records = (size - kHeaderBytes) / record_bytes(m_points);  // a torn last record is left out
  m_times.resize(records);
  for (std::uint64_t r = 0; r < records; ++r) {
    in.seekg(static_cast<std::streamoff>(kHeaderBytes + r * record_bytes(m_points)));
    in.read(reinterpret_cast<char*>(&m_times[r]), 8);
  }
  if (!in) bad(m_path, "cannot be read");
}

void ExactCoordinateReader::read(std::size_t index, std::vector<double>& xyz) const {
  require(index < m_times.size(), "coordinates '" + m_path + "': record " + std::to_string(index) + " of " +
                                      std::to_string(m_times.size()));
  std::vector<unsigned char> record(record_bytes(m_points));
  std::ifstream in(m_path, std::ios::binary);
  in.seekg(static_cast<std::streamoff>(kHeaderBytes + index * record.size()));
  if (!in.read(reinterpret_cast<char*>(record.data()), static_cast<std::streamsize>(record.size())))
    bad(m_path, "record " + std::to_string(index) + " cannot be read");
  std::uint64_t sum = 0;
  std::memcpy(&sum, record.data() + record.size() - 8, 8);
  if (sum != fnv1a(record.data(), record.size() - 8))
    bad(m_path, "record " + std::to_string(index) + " (time " + std::to_string(m_times[index]) +
                    ") fails its checksum (corrupt file)");
  xyz.resize(3 * m_points);
  if (m_points > 0) std::memcpy(xyz.data(), record.data() + 8, 24 * m_points);  // an empty vector's data() may be null
}

}  // namespace penumbra::insitu

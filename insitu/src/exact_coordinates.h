// SPDX-License-Identifier: BSD-3-Clause
// insitu/src/exact_coordinates.h -- a moving mesh's coordinates kept exactly, one record per step
#pragma once
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "penumbra/core/vec3.h"

namespace penumbra::insitu {

/// Appends one record per step to a file that starts with "PNBCOORD", a format version and the
/// point count: the step's time, its float64 xyz per point and an FNV-1a checksum of both. Each
/// record is flushed before append returns; a run that dies leaves every complete record readable
/// and a torn last one is ignored.
class ExactCoordinateWriter {
public:
  /// Creates `path` (replacing a file there). Throws Error(io_error) naming it on failure.
  ExactCoordinateWriter(std::string path, std::uint64_t point_count);
  ~ExactCoordinateWriter();
  ExactCoordinateWriter(const ExactCoordinateWriter&) = delete;
  ExactCoordinateWriter& operator=(const ExactCoordinateWriter&) = delete;
  /// Throws Error(io_error) when the record cannot be written (the file is cut back to the
  /// records before it, so that later records still follow whole ones).
  void append(double time, const std::vector<Vec3d>& points);

private:
  std::string m_path;
  std::uint64_t m_points;
  std::FILE* m_file = nullptr;
  long m_size = 0;  ///< bytes of the header and the whole records written
};

/// The records of such a file.
class ExactCoordinateReader {
public:
  /// Throws Error(io_error) naming `path` when it is not such a file or holds another point count.
  ExactCoordinateReader(std::string path, std::uint64_t point_count);
  /// The time of every complete record.
  const std::vector<double>& times() const { return m_times; }
  /// Record `index` as xyz per point; throws Error(io_error) naming the file and the record when
  /// its checksum does not match.
  void read(std::size_t index, std::vector<double>& xyz) const;

private:
  std::string m_path;
  std::uint64_t m_points;
  std::vector<double> m_times;
};

}  // namespace penumbra::insitu

// SPDX-License-Identifier: BSD-3-Clause
// insitu/src/coordinate_history.h -- reading back a moving segment's coordinates (CoordinateWriter)
#pragma once
#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "exact_coordinates.h"
#include "penumbra/compression/field_file.h"
#include "penumbra/compression/pager.h"

namespace penumbra::insitu {

/// The coordinates a segment's `coordinates` folder holds, by step time: exact steps first, then
/// the compressed epochs. A segment whose points never moved has none.
class CoordinateHistory {
public:
  /// Opens `segment_dir`/coordinates if there is one. Throws Error(io_error) naming the file for a
  /// corrupt or mismatched one (another point count, an epoch without one of its axes).
  CoordinateHistory(const std::string& segment_dir, std::uint64_t point_count);
  ~CoordinateHistory();
  /// Whether the points moved in this segment.
  bool moving() const { return m_first_time.has_value(); }
  /// The time of the first step whose coordinates are kept here (steps before it are the mesh's own).
  double first_time() const { return *m_first_time; }
  /// Whether the coordinates at `time` can be read (a run that died keeps whole windows only).
  bool has(double time) const;
  /// The coordinates at `time`, xyz per point; throws Error(invalid_argument) when none are kept.
  void read(double time, std::vector<double>& xyz);

private:
  struct Epoch {
    std::array<std::shared_ptr<compression::CompressedField>, 3> axes;
    std::array<std::unique_ptr<compression::Pager>, 3> pagers;
  };
  std::int64_t exact_index(double time) const;
  /// The epoch holding `time` in all three axes and the step there, or -1.
  std::pair<int, std::int64_t> epoch_step(double time) const;
  void open_epoch(const std::string& dir);

  std::string m_dir;
  std::uint64_t m_points;
  std::optional<double> m_first_time;
  std::unique_ptr<ExactCoordinateReader> m_exact;
  std::vector<Epoch> m_epochs;
  std::vector<double> m_axis;
};

}  // namespace penumbra::insitu

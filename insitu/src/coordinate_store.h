// SPDX-License-Identifier: BSD-3-Clause
// insitu/src/coordinate_store.h -- the coordinates of a segment whose points move, per recorded step
#pragma once
#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "config.h"
#include "exact_coordinates.h"
#include "penumbra/compression/streaming_encoder.h"
#include "penumbra/core/vec3.h"

namespace penumbra::insitu {

/// Names in a segment's `coordinates` folder.
inline constexpr const char* kFirstMovingStep = "first_step.csv";  ///< cycle,time of the first step kept here
inline constexpr const char* kExactCoordinates = "exact.pnbc";     ///< ExactCoordinateWriter's log
inline constexpr const char* kAxisNames[3] = {"x", "y", "z"};     ///< epoch-NNN/x.pnbf ...

/// Writes a moving segment's coordinates to its `coordinates` folder. Compressed with the store's
/// codec as three fields x, y, z per epoch (epoch-NNN/), each within an absolute bound of
/// altitude_fraction x the thinnest cell's altitude / sqrt(3): no point moves by more than that
/// fraction of the thinnest altitude, and moving every point by less than a quarter of it cannot
/// invert a cell (to first order), so no stored cell inverts. Where the cells have thinned to half
/// the altitude an epoch's bound was set from, the next epoch starts with a tighter bound. Steps
/// kept exactly (lossless, or a step whose drift within its window the codec refuses) go to
/// exact.pnbc in float64. first_step.csv names the first step kept, so that a reader knows which
/// steps moved even when a run died before any window was complete.
class CoordinateWriter {
public:
  /// Creates `dir`; throws Error(io_error) naming it on failure.
  CoordinateWriter(std::string dir, std::uint64_t point_count, const StoreConfig& store);
  /// Keeps `points` (in the mesh's point order) at the step; `thinnest_altitude` is the mesh's
  /// smallest tet altitude now (render::smallest_altitude). Throws Error naming the step.
  void record(double time, std::int64_t cycle, const std::vector<Vec3d>& points, double thinnest_altitude);
  /// Completes the files (idempotent).
  void finish();

private:
  void begin_epoch(double thinnest_altitude);
  void keep_exactly(double time, const std::vector<Vec3d>& points);
  void write_first_step(double time, std::int64_t cycle);

  std::string m_dir;
  std::uint64_t m_points;
  StoreConfig m_store;
  bool m_started = false;
  int m_epoch = -1;
  double m_epoch_altitude = 0;  ///< the altitude the current epoch's bound was set from
  std::array<std::unique_ptr<compression::StreamingEncoder>, 3> m_axes;
  std::unique_ptr<ExactCoordinateWriter> m_exact;
  std::vector<double> m_axis;  ///< one axis of a step, for the encoders
};

}  // namespace penumbra::insitu

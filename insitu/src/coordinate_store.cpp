// SPDX-License-Identifier: BSD-3-Clause
// insitu/src/coordinate_store.cpp -- a moving segment's coordinates: compressed epochs and exact steps
#include "coordinate_store.h"

#include <cmath>
#include <cstdio>
#include <filesystem>

#include "penumbra/core/error.h"
#include "steps_csv.h"

namespace penumbra::insitu {
namespace {

void create_directory(const std::string& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec || !std::filesystem::is_directory(dir))
    throw Error(ErrorCode::io_error, "store: cannot create '" + dir + "'" + (ec ? ": " + ec.message() : std::string()));
}

}  // namespace

CoordinateWriter::CoordinateWriter(std::string dir, std::uint64_t point_count, const StoreConfig& store)
    : m_dir(std::move(dir)), m_points(point_count), m_store(store), m_axis(point_count) {
  create_directory(m_dir);
}

void CoordinateWriter::record(double time, std::int64_t cycle, const std::vector<Vec3d>& points, double thinnest_altitude) {
  require(points.size() == m_points, "store: " + std::to_string(points.size()) + " coordinates for " +
                                         std::to_string(m_points) + " points");
  if (!m_started) write_first_step(time, cycle);
  m_started = true;
  if (m_store.coordinates.lossless) return keep_exactly(time, points);
  if (!(thinnest_altitude > 0))
    throw Error(ErrorCode::invalid_argument, "store: the coordinates at cycle " + std::to_string(cycle) +
                                                 " have a cell of zero altitude; not stored");
  if (m_epoch < 0 || thinnest_altitude < 0.5 * m_epoch_altitude) begin_epoch(thinnest_altitude);
  try {
    for (int a = 0; a < 3; ++a) {
      for (std::size_t i = 0; i < m_points; ++i) m_axis[i] = points[i][a];
      m_axes[static_cast<std::size_t>(a)]->push(time, m_axis.data());
    }
  } catch (const Error& e) {
    // The step drifted within its window beyond what the window's float32 map holds at the
    // bound: kept exactly instead (a reader takes an exact step first).
    if (e.code() != ErrorCode::invalid_argument) throw;
    keep_exactly(time, points);
  }
}

void CoordinateWriter::begin_epoch(double thinnest_altitude) {
  for (auto& axis : m_axes)
    if (axis) axis->finish();
  ++m_epoch;
  m_epoch_altitude = thinnest_altitude;
  char name[32];
  std::snprintf(name, sizeof name, "/epoch-%03d", m_epoch);
  const std::string dir = m_dir + name;
  create_directory(dir);
  compression::StreamingOptions o;
  o.vertex_count = m_points;
  o.codec = m_store.codec;
  o.codec.bound = {compression::BoundKind::absolute,
                   m_store.coordinates.altitude_fraction * thinnest_altitude / std::sqrt(3.0)};
  o.memory_budget_bytes = m_store.memory_budget_bytes;
  for (int a = 0; a < 3; ++a) {
    o.path = dir + "/" + kAxisNames[a] + ".pnbf";
    o.field_name = std::string("coordinate ") + kAxisNames[a];
    m_axes[static_cast<std::size_t>(a)] = std::make_unique<compression::StreamingEncoder>(o);
  }
}

void CoordinateWriter::keep_exactly(double time, const std::vector<Vec3d>& points) {
  if (!m_exact) m_exact = std::make_unique<ExactCoordinateWriter>(m_dir + "/" + kExactCoordinates, m_points);
  m_exact->append(time, points);
}

void CoordinateWriter::write_first_step(double time, std::int64_t cycle) {
  write_steps_csv(m_dir + "/" + kFirstMovingStep, {{cycle, time}});
}

void CoordinateWriter::finish() {
  for (auto& axis : m_axes)
    if (axis) axis->finish();
}

}  // namespace penumbra::insitu

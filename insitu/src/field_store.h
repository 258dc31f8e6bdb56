// SPDX-License-Identifier: BSD-3-Clause
// insitu/src/field_store.h -- the run's compressed field history (config "store")
#pragma once
#include <algorithm>
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "config.h"
#include "penumbra/compression/streaming_encoder.h"
#include "penumbra/core/mesh_view.h"

namespace penumbra::insitu {

class CoordinateWriter;

/// Keeps every recorded step of the rendered fields, compressed (compression::StreamingEncoder:
/// a window is trained and written on a background thread while the solver goes on). The store
/// directory holds one `segment-NNN` folder per mesh topology, each with `mesh.pnbm`, one
/// `<field>.pnbf` per field (`.partial` until finish) and `steps.csv` (cycle, time). A run that
/// dies leaves every finished window readable (insitu::StoredRun). A segment whose points move
/// (one topology) also holds their coordinates per recorded step (`coordinates/`, CoordinateWriter).
///
/// Over several ranks each rank keeps its own cells as one part: a segment is then
/// `segment-NNN/part-RRRRR/`, each part laid out as a whole segment above, and part 0 writes
/// `segment-NNN/parts.txt` (the part count), so that a reader knows a part that never began. All
/// ranks begin their segments together, so one segment number means one stretch of the run.
class FieldStore {
public:
  /// Creates the store directory; throws Error(io_error) when it cannot be created. The segments
  /// already there (an earlier run, or the run before a restart) are kept: new ones are numbered
  /// after them.
  explicit FieldStore(StoreConfig config, int part = 0, int parts = 1);
  /// Finishes the files; errors are swallowed here (call finish() to see them).
  ~FieldStore();
  FieldStore(const FieldStore&) = delete;
  FieldStore& operator=(const FieldStore&) = delete;

  /// Closes the current segment and starts the next one for `mesh`.
  void begin_segment(const MeshView& mesh);
  /// The number of the last segment begun, or found in the directory when the store was opened
  /// (-1: none); continue_after numbers the next one after `segment` (the ranks agree on the
  /// highest any of them saw).
  int last_segment() const { return m_segment; }
  void continue_after(int segment) { m_segment = std::max(m_segment, segment); }
  /// Whether `cycle` is a recorded step (every_cycles).
  bool records(std::int64_t cycle) const;
  /// Adds one step of `field` (one value per mesh point), kept as float32 around a double offset
  /// and scale per window (compression::ValueMap), so that fields of any magnitude or offset keep
  /// their variation and the error bound. Throws Error naming the field, the cycle and the point
  /// for NaN/Inf values and for a step that drifted beyond what its window's map holds: that step
  /// of that field is then not stored.
  void record(const std::string& field, double time, std::int64_t cycle, const std::vector<double>& values);
  /// The mesh's points moved under its topology: from now on the segment keeps the coordinates
  /// of every recorded step (record_points), and a replay moves the points with them.
  void points_moved() { m_moving = true; }
  bool points_move() const { return m_moving; }
  /// Keeps the coordinates at a recorded step (CoordinateWriter); `thinnest_altitude` is the
  /// mesh's smallest tet altitude now. Throws Error naming the step when they cannot be kept.
  void record_points(double time, std::int64_t cycle, const std::vector<Vec3d>& points, double thinnest_altitude);
  /// Completes every file of the current segment. Idempotent.
  void finish();

private:
  void write_steps();
  /// The step in steps.csv, once per cycle.
  void record_step(double time, std::int64_t cycle);
  StoreConfig m_config;
  int m_part = 0, m_parts = 1;
  int m_segment = -1;
  std::string m_segment_dir;
  std::uint64_t m_point_count = 0;
  std::map<std::string, std::unique_ptr<compression::StreamingEncoder>> m_encoders;
  std::vector<std::pair<std::int64_t, double>> m_steps;
  bool m_moving = false;
  std::unique_ptr<CoordinateWriter> m_coordinates;  ///< made at the first moving step
};

}  // namespace penumbra::insitu

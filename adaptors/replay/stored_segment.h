// SPDX-License-Identifier: BSD-3-Clause
// adaptors/replay/stored_segment.h -- one stored segment as its parts, and the piece a rank replays
#pragma once
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "penumbra/insitu/stored_run.h"

namespace penumbra::replay {

/// The segments of a store directory in order, or `path` itself when it is a segment. Throws
/// Error(io_error) when it holds none.
std::vector<std::string> store_segments(const std::string& path);

/// One segment of a store: a serial segment (mesh.pnbm) is one part; a segment written over
/// ranks (FieldStore: `part-RRRRR` folders and `parts.txt`) has one part per rank. Its steps are
/// those every part holds (the shortest part's, when a run died mid-window).
class StoredSegment {
public:
  /// Throws Error(io_error) naming the segment for a missing or unreadable part or parts.txt.
  explicit StoredSegment(const std::string& dir);
  const std::string& dir() const { return m_dir; }
  std::size_t part_count() const { return m_parts.size(); }
  insitu::StoredRun& part(std::size_t p) const { return *m_parts[p]; }
  std::size_t step_count() const { return m_steps; }
  double time(std::size_t step) const { return m_parts.front()->time(step); }
  std::int64_t cycle(std::size_t step) const { return m_parts.front()->cycle(step); }
  /// The fields every part with points stores (a part with no point stores none).
  const std::vector<std::string>& fields() const { return m_fields; }
  bool points_move() const;
  std::size_t cell_count() const;
  /// Keeps only the first `steps` steps (a later segment restarted from a checkpoint before them).
  void truncate(std::size_t steps);

private:
  std::string m_dir;
  std::vector<std::unique_ptr<insitu::StoredRun>> m_parts;
  std::size_t m_steps = 0;
  std::vector<std::string> m_fields;
};

/// The cells [first, last) of a segment, counted through its parts in order, as one mesh: the
/// parts that hold some of them, with all their points (a partition boundary's points once per
/// part, as the ranks published them; the renderer welds them), and per step their coordinates
/// and fields in the same order. Rank r of R replays cells [N r / R, N (r + 1) / R), so any rank
/// count replays any store, and one process replays it whole.
class StorePiece {
public:
  StorePiece(const StoredSegment& segment, std::size_t first_cell, std::size_t last_cell);
  /// The piece's mesh as the C API takes it: xyz, int64 connectivity and offsets, cell types.
  const std::vector<double>& xyz() const { return m_xyz; }
  const std::vector<std::int64_t>& connectivity() const { return m_connectivity; }
  const std::vector<std::int64_t>& offsets() const { return m_offsets; }
  const std::vector<std::uint8_t>& cell_types() const { return m_types; }
  std::size_t point_count() const { return m_xyz.size() / 3; }
  /// The coordinates at `step` into xyz() (a segment whose points move). Throws Error naming the
  /// part for a corrupt record.
  void move_to(std::size_t step);
  /// `field` at `step` for every point of the piece.
  void read(const std::string& field, std::size_t step, std::vector<double>& out);

private:
  const StoredSegment& m_segment;
  std::vector<std::size_t> m_parts;  ///< the parts the piece uses, in order
  std::vector<double> m_xyz, m_part_values;
  std::vector<std::int64_t> m_connectivity, m_offsets;
  std::vector<std::uint8_t> m_types;
};

}  // namespace penumbra::replay

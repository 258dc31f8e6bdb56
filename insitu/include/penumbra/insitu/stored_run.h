// SPDX-License-Identifier: BSD-3-Clause
// insitu/include/penumbra/insitu/stored_run.h -- reading back the compressed history a run kept
// (config "store"), to render it again after the run with another config
#pragma once
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "penumbra/core/mesh_view.h"

#include "penumbra/core/export.h"

PNB_PUBLIC_BEGIN

namespace penumbra::insitu {

/// One segment of a store directory: the mesh the solver published (one topology), its
/// coordinates at each step when its points moved, and one compressed file per stored field, all
/// over the same steps. A segment of a run that died is read up to its last complete page.
class StoredRun {
public:
  /// Opens `segment_dir` (a `segment-NNN` folder of a store directory). Throws penumbra::Error
  /// (io_error) naming the file for a missing, truncated or corrupt mesh or field file.
  static std::unique_ptr<StoredRun> open(const std::string& segment_dir);
  ~StoredRun();
  StoredRun(const StoredRun&) = delete;
  StoredRun& operator=(const StoredRun&) = delete;

  /// The stored mesh, valid as long as this object.
  const MeshView& mesh() const;
  /// Whether the mesh's points move in this segment (a Lagrangian or ALE run, one topology): each
  /// step then has its own coordinates (read_points).
  bool points_move() const;
  /// The coordinates at `step`, xyz per point (the mesh's own before the points began to move).
  /// Throws penumbra::Error naming the file for a corrupt record.
  void read_points(std::size_t step, std::vector<double>& xyz);
  /// Stored field names, sorted.
  const std::vector<std::string>& fields() const;
  /// Steps stored for every field (the shortest field's count when a run died mid-window).
  std::size_t step_count() const;
  /// Simulation time and cycle of each step.
  double time(std::size_t step) const;
  std::int64_t cycle(std::size_t step) const;
  /// Starts loading every field's page that holds `step`, in the background, for playback that
  /// begins there: a caller that sets up its renderer meanwhile does not wait at its first read.
  void start_at(std::size_t step);
  /// Decodes `field` at `step` for every point into `out` (resized). Sequential reads are
  /// paged: the next window is prefetched while the current one is read. In double the values
  /// keep what the store held of a field far from zero or beyond float32 (FieldStore::record);
  /// in float32 they are narrowed.
  void read(const std::string& field, std::size_t step, std::vector<double>& out);
  void read(const std::string& field, std::size_t step, std::vector<float>& out);

private:
  template <class T>
  void read_values(const std::string& field, std::size_t step, std::vector<T>& out);
  StoredRun();
  struct Impl;
  std::unique_ptr<Impl> m_impl;
};

}  // namespace penumbra::insitu

PNB_PUBLIC_END

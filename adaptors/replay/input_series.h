// SPDX-License-Identifier: BSD-3-Clause
// adaptors/replay/input_series.h -- the time steps of a replay INPUT, one grid per step
#pragma once
#include <cstdint>
#include <memory>
#include <string>

#include <vtkSmartPointer.h>

class vtkUnstructuredGrid;

namespace penumbra::replay {

/// One loaded time step.
struct Step {
  vtkSmartPointer<vtkUnstructuredGrid> grid;
  double time = 0.0;
  std::int64_t cycle = 0;
};

/// A sequence of time steps read from disk:
/// - `.vtu` (XML) or legacy `.vtk` unstructured grid: one step;
/// - `.pvd` (ParaView collection of .vtu/.vtk files, parts of one timestep merged);
/// - `.series` (ParaView JSON index `{"files":[{"name":..,"time":..}]}`, e.g. `x.vtk.series`);
/// - Exodus II `.e .ex2 .exo .exii .g .gen` (every time step; element blocks merged by node id).
/// Time and cycle come from the data when present (field-data `TIME`/`TimeValue` and
/// `CYCLE`/`CycleIndex`, Exodus time values), else from the index file, else the step index.
/// Errors throw penumbra::Error: io_error for a missing or unreadable file (checked for every
/// file of a series by open()), invalid_argument for an unknown format or content.
class InputSeries {
public:
  /// Opens `path`, choosing the reader by extension. Reads indexes and metadata only.
  static std::unique_ptr<InputSeries> open(const std::string& path);
  virtual ~InputSeries() = default;
  /// Number of time steps (at least 1).
  virtual std::size_t size() const = 0;
  /// Reads step `index` (< size()).
  virtual Step load(std::size_t index) = 0;
  /// Short description for logs, e.g. "Exodus II 'mug.e', 21 steps".
  virtual std::string describe() const = 0;
};

/// Reads one .vtu or legacy .vtk file into a grid (throws as above).
vtkSmartPointer<vtkUnstructuredGrid> read_grid_file(const std::string& path);

}  // namespace penumbra::replay

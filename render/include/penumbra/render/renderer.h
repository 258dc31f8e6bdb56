// SPDX-License-Identifier: BSD-3-Clause
// render/include/penumbra/render/renderer.h -- what the CPU and GPU ray casters have in common
#pragma once
#include <cstdint>
#include <vector>

#include "penumbra/render/camera.h"
#include "penumbra/render/image.h"
#include "penumbra/render/shading.h"
#include "penumbra/render/tet_mesh.h"
#include "penumbra/render/transfer_function.h"

#include "penumbra/core/export.h"

PNB_PUBLIC_BEGIN

namespace penumbra::render {

/// Options shared by the renderers.
struct RenderOptions {
  /// Rays stop once accumulated opacity exceeds this (1 disables early termination).
  double early_termination_opacity = 0.999;
  /// Lighting of the emitted colour (emission only by default).
  Shading shading;
  /// Also return each pixel's runs inside the mesh (RenderOutput::runs), for compositing with
  /// other pieces of the same scene (other ranks' partitions).
  bool ray_runs = false;
  /// The most a frame's runs may take (bytes): each pixel's list while the frame renders and the
  /// flattened RayRuns that follow, counted as 28 B per pixel and 48 B per run. A frame that
  /// needs more stops and throws Error(out_of_memory) naming what it needed, so that a rank of a
  /// run (cells dealt round-robin at a high resolution: tens of runs per pixel) fails clearly
  /// instead of exhausting its node.
  std::size_t ray_runs_memory_bytes = std::size_t{2} << 30;
};

/// One stretch of a ray inside the mesh, from where it enters to where it leaves: a ray that
/// leaves through a hole or a concavity and enters again has several. Depths are distances
/// along the ray from the camera's eye; the colour is what the run alone adds, premultiplied:
/// composited front to back, a pixel's runs give the pixel.
struct RayRun {
  float entry_depth = 0, exit_depth = 0;
  float rgba[4] = {0, 0, 0, 0};
};

/// Every pixel's runs, front to back: pixel i (row-major, top row first) has
/// runs[offsets[i]] .. runs[offsets[i + 1] - 1].
struct RayRuns {
  std::vector<std::uint32_t> offsets;
  std::vector<RayRun> runs;
  bool empty() const { return offsets.empty(); }
};

/// What one render gives: the composited image, and the runs when RenderOptions::ray_runs.
struct RenderOutput {
  Image image;
  RayRuns runs;
};

/// A ray caster of one prepared mesh (its constructor prepares the mesh: acceleration
/// structures, uploads). The runtime chooses one implementation from the config and renders
/// every camera and field through this interface.
class Renderer {
public:
  virtual ~Renderer() = default;
  /// Renders per-point `scalars` (one per mesh point; NaN = no data) through `tf` into `out`.
  virtual void render(const std::vector<float>& scalars, const TransferFunction& tf, const Camera& camera,
                      const RenderOptions& options, RenderOutput& out) = 0;
  virtual const TetMesh& mesh() const = 0;
  /// The same mesh with its points moved (move_tet_mesh of mesh(), e.g. a Lagrangian mesh a step
  /// later): what depends on the positions is rebuilt, what depends on the connectivity alone is
  /// kept, and the pictures are those of a renderer made for `moved`. Throws
  /// Error(invalid_argument) when `moved` is null or has another connectivity.
  virtual void move_points(std::shared_ptr<const TetMesh> moved) = 0;
  /// "cpu" or "gpu".
  virtual const char* backend() const = 0;
};

}  // namespace penumbra::render

PNB_PUBLIC_END

// SPDX-License-Identifier: BSD-3-Clause
// render/include/penumbra/render/cpu_ray_caster.h
#pragma once
#include <memory>
#include <vector>

#include "penumbra/render/camera.h"
#include "penumbra/render/image.h"
#include "penumbra/render/renderer.h"
#include "penumbra/render/shading.h"
#include "penumbra/render/tet_mesh.h"
#include "penumbra/render/transfer_function.h"

#include "penumbra/core/export.h"

PNB_PUBLIC_BEGIN

namespace penumbra::render {

/// Per-ray result, for tests and diagnostics.
struct RayTrace {
  double rgba[4] = {0, 0, 0, 0};  ///< premultiplied colour and opacity
  double optical_depth = 0;       ///< integral of extinction along the ray
  double length_inside = 0;       ///< total length of tet segments walked
  int segments = 0;               ///< tet segments integrated
  int entries = 0;                ///< boundary entries (1 for a convex mesh)
};

/// Multi-threaded CPU ray caster for emission-absorption through a TetMesh. Builds its
/// acceleration structures (BVH over boundary faces) once per mesh; the mesh must outlive it.
/// render() may be called concurrently from several threads.
class CpuRayCaster final : public Renderer {
public:
  explicit CpuRayCaster(std::shared_ptr<const TetMesh> mesh);
  ~CpuRayCaster();
  CpuRayCaster(const CpuRayCaster&) = delete;
  CpuRayCaster& operator=(const CpuRayCaster&) = delete;

  /// Renders per-point `scalars` (one per mesh point; NaN = no data) through `tf`.
  Image render(const std::vector<float>& scalars, const TransferFunction& tf, const Camera& camera,
               const RenderOptions& options = {}) const;
  void render(const std::vector<float>& scalars, const TransferFunction& tf, const Camera& camera,
              const RenderOptions& options, RenderOutput& out) override;
  /// Traces one ray (origin + t*unit direction, t >= 0), no early termination.
  RayTrace trace(const std::vector<float>& scalars, const TransferFunction& tf, const Ray& ray) const;

  const TetMesh& mesh() const override;
  const char* backend() const override { return "cpu"; }
  /// Keeps the walk's records and orders (Morton orders of the first positions: only locality
  /// depends on them) and re-places the points and the boundary's BVH. Not concurrent with render().
  void move_points(std::shared_ptr<const TetMesh> moved) override;

private:
  struct Impl;
  std::unique_ptr<Impl> m_impl;
};

/// Double-precision reference: for every pixel, finds all ray-tet intersections through a BVH
/// over all tets (independent of adjacency and of the walk), sorts them, and integrates each
/// segment by adaptive quadrature to 1e-9 relative. Slow; ground truth for tests and benchmarks.
Image render_reference(const TetMesh& mesh, const std::vector<float>& scalars, const TransferFunction& tf,
                       const Camera& camera);
RayTrace trace_reference(const TetMesh& mesh, const std::vector<float>& scalars, const TransferFunction& tf,
                         const Ray& ray);

}  // namespace penumbra::render

PNB_PUBLIC_END

// SPDX-License-Identifier: BSD-3-Clause
// render/src/occlusion/gpu_occlusion.h -- Gaussian cone tracing on a GPU (OpenGL 4.5
// compute shaders), for many query points per dispatch
//
// The same algorithm as ConeTracer (penumbra/render/occlusion.h): the pyramid levels and the
// precomputed cone schedule are uploaded, and one shader invocation traces one cone: the same
// 1 -> 3 -> 7 splits with the thesis's inheritance (sub-cones take the parent's optical depth; at
// 3 -> 7 the centre the mean, each border pair the closest), the same trapezoid rule, section
// weight and attenuation, trilinear fetches that read 0 beyond a level's nodes (never
// clamp-to-edge). Differences from the CPU tracer come only from float32 arithmetic (the CPU
// uses float64 on the same float32 pyramid values): ~1e-6 in transmittance. One exception: the
// 3- and 7-cone arrangements are turned about the axis by the same rule as ConeTracer (helper
// axis x while |axis.x| < 1/phi = 0.618..., else y); an axis within float rounding of that switch
// may take the other arrangement on one path, a difference of up to a few 1e-2 at that apex. The
// switch sits at an irrational value so that axes between round coordinates never meet it.
//
// Typical use, per step: GpuExtinctionPyramid::update(pyramid) after the CPU pyramid is rebuilt,
// then one GpuConeTracer per cone kind (occlusion, shadow) and one call per eye or light:
// transmittance() for explicit points, pre_illumination() for the object-space grid (every node
// in one dispatch), at_mesh_points() for the per-point field that evaluate_at_points() gives.
// Without EGL (PNB_ENABLE_EGL=OFF) every constructor throws Error(backend_unavailable).
#pragma once
#include <array>
#include <memory>
#include <vector>

#include "penumbra/render/gpu_ray_caster.h"
#include "occlusion/occlusion_internals.h"

namespace penumbra::render {

/// The ExtinctionPyramid's levels held in one storage buffer on a device, with the compiled
/// cone-tracing program and the points of the last mesh a tracer evaluated. Keeps a pointer to the
/// host pyramid (its sigmas and bounds give the cone schedule), which must outlive this object or be
/// replaced by update().
class GpuExtinctionPyramid {
public:
  /// Uploads `pyramid`. Throws Error(invalid_argument) for a null device or an empty pyramid,
  /// Error(out_of_memory) when the levels exceed the device's limits, Error(backend_unavailable)
  /// when the shader does not compile or the build has no GPU backend.
  GpuExtinctionPyramid(std::shared_ptr<GpuDevice> device, const ExtinctionPyramid& pyramid);
  ~GpuExtinctionPyramid();
  GpuExtinctionPyramid(const GpuExtinctionPyramid&) = delete;
  GpuExtinctionPyramid& operator=(const GpuExtinctionPyramid&) = delete;

  /// Replaces the levels (a new step or transfer function); the buffer is reused when it fits.
  void update(const ExtinctionPyramid& pyramid);
  const ExtinctionPyramid& host() const;
  /// Bytes of the levels on the device.
  std::size_t level_bytes() const;
  /// Wall-clock time of the last upload (conversion and transfer), in milliseconds.
  double upload_ms() const;

  struct Impl;
  Impl& impl() const { return *m_impl; }

private:
  std::unique_ptr<Impl> m_impl;
};

/// The levels ExtinctionPyramid(grid, options) builds, filtered on the device instead: the same
/// lattices, taps and opacity conversion, float32 sums (the CPU sums in float64; see
/// gpu_cone_tracer_test.cpp for the agreement). For timing and checking the GPU build; the tracer
/// still takes an ExtinctionPyramid, which cannot be made from given levels yet.
struct GpuPyramidLevels {
  std::vector<PyramidLevel> levels;
  double build_ms = 0;   ///< everything: program, buffers, upload, passes, read-back
  double upload_ms = 0;  ///< the grid to the device (and its opacity conversion)
  double filter_ms = 0;  ///< the separable passes of every level, finished
};
/// Throws as ExtinctionPyramid's constructor for bad input, Error(out_of_memory) beyond the
/// device's limits, Error(backend_unavailable) without a GPU backend.
GpuPyramidLevels gpu_build_pyramid_levels(const std::shared_ptr<GpuDevice>& device, const ExtinctionGrid& grid,
                                          const PyramidOptions& options = {});

/// Where a cone points: towards an eye (directional occlusion, thesis sec. 3.3.1; the cone runs its
/// full length) or towards a light (shadows, sec. 3.3.2; stops at point and spot lights, 0 outside a
/// spot's cone) -- exactly directional_occlusion() and shadow_transmittance().
struct ConeTarget {
  enum class Kind { eye, light };
  Kind kind = Kind::eye;
  Vec3d eye{0, 0, 0};
  ShadowLight light;

  static ConeTarget towards_eye(const Vec3d& eye) {
    ConeTarget t;
    t.kind = Kind::eye;
    t.eye = eye;
    return t;
  }
  static ConeTarget towards_light(const ShadowLight& light) {
    ConeTarget t;
    t.kind = Kind::light;
    t.light = light;
    return t;
  }
};

/// The object-space volume computed on the device: the grid of PreIlluminationVolume (same nodes for
/// the same bounds and resolution), values node i + dims[0] * (j + dims[1] * k).
struct GpuPreIllumination {
  std::array<int, 3> dims{0, 0, 0};
  Vec3d lo, spacing;
  std::vector<float> values;
  double build_ms = 0;  ///< dispatch and read-back
  /// As PreIlluminationVolume::sample: trilinear, clamped to the grid.
  double sample(const Vec3d& p) const;
};

/// The nodes PreIlluminationVolume(bounds, resolution, ...) uses, with every value 1. Throws
/// Error(invalid_argument) for resolution < 2 or empty / non-finite bounds.
GpuPreIllumination gpu_pre_illumination_grid(const Bounds& bounds, int resolution);

/// Traces cones of one ConeOptions through a GpuExtinctionPyramid. Calls on one device are
/// serialised; the object may be used from any thread.
class GpuConeTracer {
public:
  /// Builds the schedule as ConeTracer does (same checks, same errors) and uploads it. `pyramid`
  /// must outlive the tracer; after pyramid.update() make a new tracer (the schedule depends on
  /// sigma0 and the bounds): the old one throws Error(invalid_operation).
  GpuConeTracer(const GpuExtinctionPyramid& pyramid, const ConeOptions& options);
  ~GpuConeTracer();
  GpuConeTracer(const GpuConeTracer&) = delete;
  GpuConeTracer& operator=(const GpuConeTracer&) = delete;

  /// The host tracer with the same schedule (for reference values and its length/gap).
  const ConeTracer& host() const;

  /// Transmittance of the cone from every point towards `target`, one dispatch per 4M points.
  std::vector<float> transmittance(const ConeTarget& target, const std::vector<Vec3d>& points) const;
  /// The object-space grid (PreIlluminationVolume's nodes over `bounds`), all nodes in one
  /// dispatch. Throws Error(invalid_argument) as PreIlluminationVolume does.
  GpuPreIllumination pre_illumination(const ConeTarget& target, const Bounds& bounds, int resolution) const;
  /// What evaluate_at_points(mesh, value) gives for value = the cone towards `target`: one value
  /// per mesh point, 1 at points no tet uses. With `volume_resolution` > 0 the values are instead
  /// the object-space grid over the pyramid's bounds sampled at the points (both on the device; only
  /// the per-point values are read back). The mesh's points are uploaded once per mesh and held by
  /// the pyramid (shared by its tracers, kept across update()).
  std::vector<float> at_mesh_points(const ConeTarget& target, const std::shared_ptr<const TetMesh>& mesh,
                                    int volume_resolution = 0) const;

private:
  struct Impl;
  std::unique_ptr<Impl> m_impl;
};

}  // namespace penumbra::render

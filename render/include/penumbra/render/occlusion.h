// SPDX-License-Identifier: BSD-3-Clause
// render/include/penumbra/render/occlusion.h -- the light field of lighting model "occlusion":
// directional ambient occlusion towards the camera times cone-traced shadows from the lights
// (Gaussian cone tracing through a filtered pyramid of extinction; docs/cone_tracing.md)
#pragma once
#include <functional>
#include <memory>
#include <vector>

#include "penumbra/core/vec3.h"
#include "penumbra/render/egl_device.h"
#include "penumbra/render/light_volume.h"
#include "penumbra/render/tet_mesh.h"
#include "penumbra/render/transfer_function.h"

#include "penumbra/core/export.h"

PNB_PUBLIC_BEGIN

namespace penumbra::render {

class GpuDevice;

/// Which pyramid level a cone section of radius r reads (docs/cone_tracing.md, "Level selection").
enum class LevelSelection {
  continuous,  ///< sigma = r / 2, the two levels around it blended: the default
  /// One whole level: the finest with r <= r_c = 2 sigma_l (sec. 3.2.3), stepping at r_c; level 0
  /// for sections narrower than 2 sigma0 too: the thesis's schedule.
  thesis,
};

/// Where cone tracing is evaluated: at every mesh point (per camera), on a pre-illumination grid
/// sampled at the points, or at every sample of every ray (image space).
enum class OcclusionSpace { points, volume, image };

/// Cone-traced directional occlusion and shadows.
struct OcclusionSettings {
  double aperture_deg = 30.0;  ///< occlusion cones towards the viewer
  int splits = 3;              ///< 1, 3 or 7
  int grid_resolution = 128;   ///< extinction grid nodes along the longest side
  double attenuation = 1.0;    ///< global alpha
  OcclusionSpace space = OcclusionSpace::points;
  int volume_resolution = 64;
  bool shadows = true;         ///< narrow cones towards each light
  double shadow_aperture_deg = 2.0;
  int shadow_splits = 1;
  /// Pyramid level a cone section reads: continuous (default) or the thesis's whole levels.
  LevelSelection level = LevelSelection::continuous;
  /// Over several ranks, each with its own cells: the extinction grid spans these bounds (the
  /// union of every rank's, the same on every rank) so that the ranks' grids can be merged
  /// (OcclusionLighting::combine_extinction). Empty: the mesh's bounds.
  Bounds grid_bounds;
};

/// A shadow cone's first gap: the segment from a point towards a light that the cone skips and
/// that is integrated exactly through the tets instead.
struct GapSegment {
  Vec3d start, direction;  ///< direction: any length > 0
  double length = 0;
};

/// Per field: the extinction pyramid of the current step (rebuilt by set_field) and, per camera,
/// L(x) = AO(x, eye) x sum_k colour_k shadow_k(x) at every mesh point (AO alone without lights or
/// with shadows off), for the ray caster's light-field shading. Shadows are the light that
/// reaches x: each shadow cone's gap is integrated exactly through the tets.
///
/// With a GPU device the cones are traced on it: the pyramid is resampled and filtered on the
/// CPU, uploaded once per step, and every per-point field (and in space "volume" the
/// pre-illumination grid) is one dispatch per eye or light; the shadows' gaps are integrated on
/// the CPU. light_at() (image space, CPU ray caster only) always traces on the CPU.
class OcclusionLighting {
public:
  OcclusionLighting(std::shared_ptr<const TetMesh> mesh, const OcclusionSettings& settings, std::vector<Light> lights,
                    std::shared_ptr<GpuDevice> gpu = nullptr);
  ~OcclusionLighting();
  OcclusionLighting(const OcclusionLighting&) = delete;
  OcclusionLighting& operator=(const OcclusionLighting&) = delete;
  /// Resamples extinction through `tf`, rebuilds the pyramid and the shadow factors: the three
  /// calls below in one.
  void set_field(const std::vector<float>& scalars, const TransferFunction& tf);
  /// set_field in halves around the merge of the ranks' extinction grids, for a run over ranks:
  /// resample_field (validates, resamples this rank's cells), combine_extinction (collective
  /// whenever `combine` is: it replaces the grid by its element-wise maximum over the ranks, the
  /// whole mesh's grid, so cones see every rank's cells), finish_field (the pyramid, the tracers,
  /// the shadows). Shadow cones integrate their first gap through this rank's cells only.
  void resample_field(const std::vector<float>& scalars, const TransferFunction& tf);
  using ExtinctionCombine = std::function<void(std::vector<float>& tau)>;
  void combine_extinction(const ExtinctionCombine& combine);
  /// Over several ranks, between combine_extinction and finish_field: the shadow gaps that leave
  /// this rank's cells, per light and point. Every rank integrates them through its own cells
  /// (gap_depths) and add_gap_depths hands back the sums, so each gap is integrated through the
  /// whole mesh: the transmittance factors over disjoint cells. (Image space, whose gaps start at
  /// every ray sample, integrates them through this rank's cells alone: none are listed.)
  std::vector<GapSegment> open_gaps();
  /// The optical depth of each segment through this mesh's tets (0 without shadows). Thread-safe.
  std::vector<double> gap_depths(const std::vector<GapSegment>& segments) const;
  /// Per open_gaps() entry, the depth the other ranks' cells add to it.
  void add_gap_depths(const std::vector<double>& depths);
  void finish_field();
  /// The light field (3 floats per point) seen from `eye`.
  const std::vector<float>& light_rgb(const Vec3d& eye);
  /// Image space: the same light evaluated at any point x (every sample of every ray), seen
  /// from `eye`; valid until the next set_field.
  std::function<void(const Vec3d&, double[3])> light_at(const Vec3d& eye) const;

private:
  struct Impl;
  std::unique_ptr<Impl> m_impl;
};

}  // namespace penumbra::render

PNB_PUBLIC_END

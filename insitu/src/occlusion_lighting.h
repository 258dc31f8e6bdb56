// SPDX-License-Identifier: BSD-3-Clause
// insitu/src/occlusion_lighting.h -- the light field of lighting model "occlusion": directional
// ambient occlusion towards the camera times cone-traced shadows from the lights
#pragma once
#include <functional>
#include <memory>
#include <vector>

#include "config.h"
#include "penumbra/render/gpu_occlusion.h"
#include "penumbra/render/occlusion.h"
#include "penumbra/render/tet_mesh.h"

namespace penumbra::insitu {

/// Per field: the extinction pyramid of the current step (rebuilt by set_field) and, per camera,
/// L(x) = AO(x, eye) x sum_k colour_k shadow_k(x) at every mesh point (AO alone without lights or
/// with shadows off), for the ray caster's light-field shading. Shadows are the light that
/// reaches x: each shadow cone's gap h0 is integrated exactly through the tets (render::GapDepth).
///
/// With a GPU device (backend gpu) the cones are traced on it: the pyramid is resampled and
/// filtered on the CPU, uploaded once per step, and every per-point field (and in space "volume"
/// the pre-illumination grid) is one dispatch per eye or light; the shadows' gaps are integrated
/// on the CPU. light_at() (image space, CPU ray caster only) always traces on the CPU.
class OcclusionLighting {
public:
  OcclusionLighting(std::shared_ptr<const render::TetMesh> mesh, const OcclusionConfig& config,
                    std::vector<render::Light> lights, std::shared_ptr<render::GpuDevice> gpu = nullptr);
  /// Resamples extinction through `tf`, rebuilds the pyramid and the shadow factors.
  void set_field(const std::vector<float>& scalars, const render::TransferFunction& tf);
  /// The light field (3 floats per point) seen from `eye`.
  const std::vector<float>& light_rgb(const Vec3d& eye);
  /// Image space: the same light evaluated at any point x (every sample of every ray), seen
  /// from `eye`; valid until the next set_field.
  std::function<void(const Vec3d&, double[3])> light_at(const Vec3d& eye) const;

private:
  std::shared_ptr<const render::TetMesh> m_mesh;
  OcclusionConfig m_config;
  std::vector<render::Light> m_lights;
  render::ExtinctionResampler m_resampler;
  render::ExtinctionPyramid m_pyramid;
  std::unique_ptr<render::ConeTracer> m_ao_tracer, m_shadow_tracer;
  // Exact depth over the shadow cones' gap (built on the first step with shadows: a BVH per mesh).
  std::unique_ptr<render::GapDepth> m_gap_depth;
  // The GPU path (null without a device); declared after m_pyramid, which they point to.
  std::shared_ptr<render::GpuDevice> m_gpu;
  std::unique_ptr<render::GpuExtinctionPyramid> m_gpu_pyramid;
  std::unique_ptr<render::GpuConeTracer> m_gpu_ao, m_gpu_shadow;
  std::vector<float> m_shadow_rgb;  ///< sum_k colour_k shadow_k per point, 3 per point; empty: white
  std::vector<float> m_rgb;
};

}  // namespace penumbra::insitu

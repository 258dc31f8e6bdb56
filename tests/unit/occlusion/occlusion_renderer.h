// SPDX-License-Identifier: BSD-3-Clause
// tests/unit/occlusion/occlusion_renderer.h -- a scene lit by the in-situ occlusion lighting
// (render::OcclusionLighting, penumbra/render/occlusion.h) as a renderer of the invariance and property tests
#pragma once
#include "invariance.h"
#include "penumbra/render/occlusion.h"

namespace penumbra::test {

/// Occlusion towards the camera's eye and shadows towards the scene's lights, in `space`, with
/// cones traced on the GPU device or the CPU; the frame ray cast by the caster of that backend.
inline Renderer occlusion(bool gpu, render::OcclusionSpace space) {
  return [=](const std::shared_ptr<const render::TetMesh>& mesh, const Scene& s) {
    render::OcclusionSettings config;
    config.grid_resolution = 32;
    config.volume_resolution = 16;
    config.space = space;
    render::OcclusionLighting lighting(mesh, config, s.lights, gpu ? device() : nullptr);
    lighting.set_field(s.scalars, s.tf);
    Scene lit = s;
    lit.options.shading.model = render::LightingModel::light_volume;
    if (space == render::OcclusionSpace::image) {
      lit.options.shading.light_at = lighting.light_at(s.camera.eye);
      return render_cpu(mesh, lit);
    }
    lit.options.shading.light_rgb = &lighting.light_rgb(s.camera.eye);
    return gpu ? render_gpu(mesh, lit) : render_cpu(mesh, lit);
  };
}

}  // namespace penumbra::test

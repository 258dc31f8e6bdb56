// SPDX-License-Identifier: BSD-3-Clause
// render/src/occlusion/occlusion_lighting.cpp -- cone-traced occlusion and shadows as a per-point
// light field
#include "penumbra/render/occlusion.h"

#include "occlusion/gpu_occlusion.h"
#include "occlusion/occlusion_internals.h"

namespace penumbra::render {
namespace {

render::ShadowLight shadow_light(const render::Light& l) {
  render::ShadowLight s;
  s.kind = l.kind == render::Light::Kind::directional ? render::ShadowLight::Kind::directional
                                                      : render::ShadowLight::Kind::point;
  s.vector = l.vector;
  return s;
}

}  // namespace

struct OcclusionLighting::Impl {
  Impl(std::shared_ptr<const TetMesh> mesh, const OcclusionSettings& config, std::vector<Light> lights,
       std::shared_ptr<GpuDevice> gpu)
      : m_mesh(std::move(mesh)),
        m_config(config),
        m_lights(std::move(lights)),
        m_resampler(m_mesh, config.grid_resolution),
        m_gpu(std::move(gpu)) {}
  void set_field(const std::vector<float>& scalars, const TransferFunction& tf);
  const std::vector<float>& light_rgb(const Vec3d& eye);
  std::function<void(const Vec3d&, double[3])> light_at(const Vec3d& eye) const;

  std::shared_ptr<const TetMesh> m_mesh;
  OcclusionSettings m_config;
  std::vector<Light> m_lights;
  ExtinctionResampler m_resampler;
  ExtinctionPyramid m_pyramid;
  std::unique_ptr<ConeTracer> m_ao_tracer, m_shadow_tracer;
  // Exact depth over the shadow cones' gap (built on the first step with shadows: a BVH per mesh).
  std::unique_ptr<GapDepth> m_gap_depth;
  // The GPU path (null without a device); declared after m_pyramid, which they point to.
  std::shared_ptr<GpuDevice> m_gpu;
  std::unique_ptr<GpuExtinctionPyramid> m_gpu_pyramid;
  std::unique_ptr<GpuConeTracer> m_gpu_ao, m_gpu_shadow;
  std::vector<float> m_shadow_rgb;  ///< sum_k colour_k shadow_k per point, 3 per point; empty: white
  std::vector<float> m_rgb;
};

OcclusionLighting::OcclusionLighting(std::shared_ptr<const TetMesh> mesh, const OcclusionSettings& settings,
                                     std::vector<Light> lights, std::shared_ptr<GpuDevice> gpu)
    : m_impl(std::make_unique<Impl>(std::move(mesh), settings, std::move(lights), std::move(gpu))) {}

OcclusionLighting::~OcclusionLighting() = default;

void OcclusionLighting::set_field(const std::vector<float>& scalars, const TransferFunction& tf) {
  m_impl->set_field(scalars, tf);
}

const std::vector<float>& OcclusionLighting::light_rgb(const Vec3d& eye) { return m_impl->light_rgb(eye); }

std::function<void(const Vec3d&, double[3])> OcclusionLighting::light_at(const Vec3d& eye) const {
  return m_impl->light_at(eye);
}

void OcclusionLighting::Impl::set_field(const std::vector<float>& scalars, const TransferFunction& tf) {
  m_gpu_ao.reset();
  m_gpu_shadow.reset();
  m_ao_tracer.reset();
  m_shadow_tracer.reset();
  m_pyramid = render::ExtinctionPyramid(m_resampler.resample(scalars, tf));
  render::ConeOptions ao = render::ConeOptions::occlusion(m_config.aperture_deg, m_config.splits);
  ao.attenuation = m_config.attenuation;
  ao.level = m_config.level;
  m_ao_tracer = std::make_unique<render::ConeTracer>(m_pyramid, ao);
  if (m_gpu) {
    if (m_gpu_pyramid)
      m_gpu_pyramid->update(m_pyramid);
    else
      m_gpu_pyramid = std::make_unique<render::GpuExtinctionPyramid>(m_gpu, m_pyramid);
    m_gpu_ao = std::make_unique<render::GpuConeTracer>(*m_gpu_pyramid, ao);
  }
  m_shadow_rgb.clear();
  if (!m_config.shadows || m_lights.empty()) return;
  render::ConeOptions so = render::ConeOptions::shadow(m_config.shadow_aperture_deg, m_config.shadow_splits);
  so.attenuation = m_config.attenuation;
  so.level = m_config.level;
  m_shadow_tracer = std::make_unique<render::ConeTracer>(m_pyramid, so);
  if (!m_gap_depth) m_gap_depth = std::make_unique<render::GapDepth>(m_mesh);
  m_gap_depth->set_field(scalars, tf);
  if (m_config.space == OcclusionSpace::image) return;  // evaluated per sample instead
  if (m_gpu) m_gpu_shadow = std::make_unique<render::GpuConeTracer>(*m_gpu_pyramid, so);
  const render::ConeTracer& tracer = *m_shadow_tracer;
  const render::GapDepth& gap = *m_gap_depth;
  m_shadow_rgb.assign(3 * m_mesh->points.size(), 0.0f);
  for (const render::Light& light : m_lights) {
    const render::ShadowLight sl = shadow_light(light);
    std::vector<float> t;
    if (m_gpu_shadow) {
      t = m_gpu_shadow->at_mesh_points(render::ConeTarget::towards_light(sl), m_mesh);
      const std::vector<float> through_gap = render::evaluate_at_points(
          *m_mesh, [&](const Vec3d& x) { return render::gap_transmittance(tracer, sl, x, gap); });
      for (std::size_t p = 0; p < t.size(); ++p) t[p] *= through_gap[p];
    } else {
      t = render::evaluate_at_points(*m_mesh, [&](const Vec3d& x) { return render::shadow_transmittance(tracer, sl, x, gap); });
    }
    for (std::size_t p = 0; p < t.size(); ++p)
      for (int c = 0; c < 3; ++c) m_shadow_rgb[3 * p + c] += static_cast<float>(t[p] * light.color[static_cast<std::size_t>(c)]);
  }
}

const std::vector<float>& OcclusionLighting::Impl::light_rgb(const Vec3d& eye) {
  const render::ConeTracer& tracer = *m_ao_tracer;
  auto occlusion = [&](const Vec3d& x) { return render::directional_occlusion(tracer, x, eye); };
  std::vector<float> factor;
  if (m_gpu_ao) {
    // Per point, or through the object-space grid (both on the device).
    const int volume = m_config.space == OcclusionSpace::volume ? m_config.volume_resolution : 0;
    factor = m_gpu_ao->at_mesh_points(render::ConeTarget::towards_eye(eye), m_mesh, volume);
  } else if (m_config.space == OcclusionSpace::volume) {
    // Object space: the occlusion on a grid, sampled at the points (sec. 3.3.3).
    const render::PreIlluminationVolume volume(m_pyramid.bounds(), m_config.volume_resolution, occlusion);
    factor = render::evaluate_at_points(*m_mesh, [&](const Vec3d& x) { return volume.sample(x); });
  } else {
    factor = render::evaluate_at_points(*m_mesh, occlusion);
  }
  m_rgb.resize(3 * factor.size());
  for (std::size_t p = 0; p < factor.size(); ++p)
    for (int c = 0; c < 3; ++c)
      m_rgb[3 * p + c] = factor[p] * (m_shadow_rgb.empty() ? 1.0f : m_shadow_rgb[3 * p + c]);
  return m_rgb;
}

std::function<void(const Vec3d&, double[3])> OcclusionLighting::Impl::light_at(const Vec3d& eye) const {
  return [this, eye](const Vec3d& x, double rgb[3]) {
    const double ao = render::directional_occlusion(*m_ao_tracer, x, eye);
    double light[3] = {1, 1, 1};
    if (m_shadow_tracer) {
      light[0] = light[1] = light[2] = 0;
      for (const render::Light& l : m_lights) {
        const double t = render::shadow_transmittance(*m_shadow_tracer, shadow_light(l), x, *m_gap_depth);
        for (int c = 0; c < 3; ++c) light[c] += t * l.color[static_cast<std::size_t>(c)];
      }
    }
    for (int c = 0; c < 3; ++c) rgb[c] = ao * light[c];
  };
}

}  // namespace penumbra::render

// SPDX-License-Identifier: BSD-3-Clause
// render/src/occlusion/occlusion_lighting.cpp -- cone-traced occlusion and shadows as a per-point
// light field
#include "penumbra/render/occlusion.h"

#include <cmath>
#include <cstdint>
#include <string>
#include <utility>

#include "penumbra/core/error.h"
#include "penumbra/core/thread_pool.h"

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
        m_resampler(m_mesh, config.grid_resolution, config.grid_bounds),
        m_gpu(std::move(gpu)) {}
  void resample_field(const std::vector<float>& scalars, const TransferFunction& tf);
  void build_tracers();
  render::ConeOptions ao_options() const;
  render::ConeOptions shadow_options() const;
  bool with_shadows() const { return m_config.shadows && !m_lights.empty(); }
  GapSegment gap_of(const Light& light, const Vec3d& x) const;
  std::vector<GapSegment> open_gaps();
  std::vector<double> gap_depths(const std::vector<GapSegment>& segments) const;
  void add_gap_depths(const std::vector<double>& depths);
  void finish_field();
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
  // resample_field's grid, until finish_field; whether the tracers are built on it.
  ExtinctionGrid m_grid;
  bool m_resampled = false, m_tracers_ready = false;
  // The gaps open_gaps() listed (light, point), and per light the depth other ranks' cells add
  // to a point's gap.
  struct OpenGap {
    std::uint32_t light, point;
  };
  std::vector<OpenGap> m_open;
  std::vector<std::vector<std::pair<std::uint32_t, double>>> m_extra_gap;
  std::vector<float> m_shadow_rgb;  ///< sum_k colour_k shadow_k per point, 3 per point; empty: white
  std::vector<float> m_rgb;
};

OcclusionLighting::OcclusionLighting(std::shared_ptr<const TetMesh> mesh, const OcclusionSettings& settings,
                                     std::vector<Light> lights, std::shared_ptr<GpuDevice> gpu)
    : m_impl(std::make_unique<Impl>(std::move(mesh), settings, std::move(lights), std::move(gpu))) {}

OcclusionLighting::~OcclusionLighting() = default;

void OcclusionLighting::set_field(const std::vector<float>& scalars, const TransferFunction& tf) {
  m_impl->resample_field(scalars, tf);
  m_impl->finish_field();
}

void OcclusionLighting::resample_field(const std::vector<float>& scalars, const TransferFunction& tf) {
  m_impl->resample_field(scalars, tf);
}

void OcclusionLighting::combine_extinction(const ExtinctionCombine& combine) {
  require(static_cast<bool>(combine), "OcclusionLighting::combine_extinction: combine is empty; expected a function");
  require(m_impl->m_resampled, "OcclusionLighting::combine_extinction: no field resampled; call resample_field first");
  const std::size_t n = m_impl->m_grid.tau.size();
  combine(m_impl->m_grid.tau);
  if (m_impl->m_grid.tau.size() != n)
    throw Error(ErrorCode::internal_error, "OcclusionLighting::combine_extinction: the combination resized the grid (" +
                                               std::to_string(n) + " nodes)");
}

std::vector<GapSegment> OcclusionLighting::open_gaps() {
  require(m_impl->m_resampled, "OcclusionLighting::open_gaps: no field resampled; call resample_field first");
  return m_impl->open_gaps();
}

std::vector<double> OcclusionLighting::gap_depths(const std::vector<GapSegment>& segments) const {
  return m_impl->gap_depths(segments);
}

void OcclusionLighting::add_gap_depths(const std::vector<double>& depths) { m_impl->add_gap_depths(depths); }

void OcclusionLighting::finish_field() {
  require(m_impl->m_resampled, "OcclusionLighting::finish_field: no field resampled; call resample_field first");
  m_impl->finish_field();
}

const std::vector<float>& OcclusionLighting::light_rgb(const Vec3d& eye) { return m_impl->light_rgb(eye); }

std::function<void(const Vec3d&, double[3])> OcclusionLighting::light_at(const Vec3d& eye) const {
  return m_impl->light_at(eye);
}

void OcclusionLighting::Impl::resample_field(const std::vector<float>& scalars, const TransferFunction& tf) {
  m_grid = m_resampler.resample(scalars, tf);
  m_resampled = true;
  m_tracers_ready = false;
  m_extra_gap.assign(m_lights.size(), {});
  if (!with_shadows()) return;
  if (!m_gap_depth) m_gap_depth = std::make_unique<render::GapDepth>(m_mesh);
  m_gap_depth->set_field(scalars, tf);
}

// The pyramid of the (merged) grid and the CPU's cone tracers.
void OcclusionLighting::Impl::build_tracers() {
  if (m_tracers_ready) return;
  m_gpu_ao.reset();
  m_gpu_shadow.reset();
  m_ao_tracer.reset();
  m_shadow_tracer.reset();
  m_pyramid = render::ExtinctionPyramid(m_grid);
  m_ao_tracer = std::make_unique<render::ConeTracer>(m_pyramid, ao_options());
  if (with_shadows()) m_shadow_tracer = std::make_unique<render::ConeTracer>(m_pyramid, shadow_options());
  m_tracers_ready = true;
}

render::ConeOptions OcclusionLighting::Impl::ao_options() const {
  render::ConeOptions ao = render::ConeOptions::occlusion(m_config.aperture_deg, m_config.splits);
  ao.attenuation = m_config.attenuation;
  ao.level = m_config.level;
  return ao;
}

render::ConeOptions OcclusionLighting::Impl::shadow_options() const {
  render::ConeOptions so = render::ConeOptions::shadow(m_config.shadow_aperture_deg, m_config.shadow_splits);
  so.attenuation = m_config.attenuation;
  so.level = m_config.level;
  return so;
}

// Light k's gap at point p: the segment the shadow cone skips (gap_transmittance's).
GapSegment OcclusionLighting::Impl::gap_of(const Light& light, const Vec3d& x) const {
  const double h0 = m_shadow_tracer->gap();
  if (light.kind == Light::Kind::directional) return {x, -light.vector, h0};
  const Vec3d to_light = light.vector - x;
  return {x, to_light, std::min(h0, length(to_light))};
}

std::vector<GapSegment> OcclusionLighting::Impl::open_gaps() {
  build_tracers();
  m_open.clear();
  std::vector<GapSegment> open;
  if (!with_shadows() || m_config.space == OcclusionSpace::image) return open;
  const std::size_t np = m_mesh->points.size();
  std::vector<std::uint8_t> leaves(np);
  for (std::size_t k = 0; k < m_lights.size(); ++k) {
    parallel_for(np, 1024, [&](std::size_t b, std::size_t e) {
      for (std::size_t p = b; p < e; ++p) {
        const GapSegment g = gap_of(m_lights[k], m_mesh->points[p]);
        double covered = 0;
        m_gap_depth->depth(g.start, g.direction, g.length, &covered);
        leaves[p] = covered < g.length * (1 - 1e-9) ? 1 : 0;
      }
    });
    for (std::size_t p = 0; p < np; ++p)
      if (leaves[p]) {
        open.push_back(gap_of(m_lights[k], m_mesh->points[p]));
        m_open.push_back({static_cast<std::uint32_t>(k), static_cast<std::uint32_t>(p)});
      }
  }
  return open;
}

std::vector<double> OcclusionLighting::Impl::gap_depths(const std::vector<GapSegment>& segments) const {
  std::vector<double> depth(segments.size(), 0.0);
  if (!m_gap_depth) return depth;  // no shadows here: then none anywhere (the ranks share a config)
  parallel_for(segments.size(), 256, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) depth[i] = m_gap_depth->depth(segments[i].start, segments[i].direction, segments[i].length);
  });
  return depth;
}

void OcclusionLighting::Impl::add_gap_depths(const std::vector<double>& depths) {
  require(depths.size() == m_open.size(), "OcclusionLighting::add_gap_depths: " + std::to_string(depths.size()) +
                                              " depths for " + std::to_string(m_open.size()) + " open gaps");
  for (std::size_t i = 0; i < depths.size(); ++i)
    if (depths[i] > 0) m_extra_gap[m_open[i].light].push_back({m_open[i].point, depths[i]});
}

void OcclusionLighting::Impl::finish_field() {
  build_tracers();
  m_resampled = false;
  if (m_gpu) {
    if (m_gpu_pyramid)
      m_gpu_pyramid->update(m_pyramid);
    else
      m_gpu_pyramid = std::make_unique<render::GpuExtinctionPyramid>(m_gpu, m_pyramid);
    m_gpu_ao = std::make_unique<render::GpuConeTracer>(*m_gpu_pyramid, ao_options());
  }
  m_shadow_rgb.clear();
  if (!with_shadows() || m_config.space == OcclusionSpace::image) return;  // image space: per sample instead
  if (m_gpu) m_gpu_shadow = std::make_unique<render::GpuConeTracer>(*m_gpu_pyramid, shadow_options());
  const render::ConeTracer& tracer = *m_shadow_tracer;
  const render::GapDepth& gap = *m_gap_depth;
  m_shadow_rgb.assign(3 * m_mesh->points.size(), 0.0f);
  for (std::size_t k = 0; k < m_lights.size(); ++k) {
    const render::Light& light = m_lights[k];
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
    // Other ranks' cells in the gap (add_gap_depths).
    for (const auto& [p, depth] : m_extra_gap[k]) t[p] = static_cast<float>(t[p] * std::exp(-depth));
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

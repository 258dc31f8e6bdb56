// SPDX-License-Identifier: BSD-3-Clause
// render/src/occlusion/gl/gpu_cone_tracer.cpp -- buffers, uniforms and dispatches of the
// cone-tracing shader (render/shaders/cone_trace.comp)
//
// Device layout: every pyramid level, then the unfiltered grid (ExtinctionPyramid::fine()), in one
// float32 storage buffer, a 48-byte header per level
// (dims + offset, lo, 1 / spacing), the host ConeTracer's schedule at 32 bytes per sample, query
// points as float32 xyz and one float32 result per query. Positions go to the device relative to
// the pyramid's bounds centre.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>

#include "shader_constants.h"
#include "occlusion_gl_util.h"
#include "penumbra/core/error.h"
#include "penumbra/core/local_frame.h"
#include "occlusion/gpu_occlusion.h"

namespace penumbra::render {
namespace gpu {
extern const char* const kConeTraceShader;  // render/shaders/cone_trace.comp, embedded at build time
}  // namespace gpu

namespace {

using gpu::Clock;
using gpu::CurrentContext;
using gpu::DeviceBuffer;
using gpu::GlApi;

enum Binding : GLuint { kLevels, kInfos, kSchedule, kPoints, kResult, kGrid, kBindingCount };
constexpr int kLocalSize = shader::kConeTraceGroup;  // cone_trace.comp's local_size_x
constexpr double kPi = 3.14159265358979323846;

std::vector<float> local_xyz(const std::vector<Vec3d>& points, const LocalFrame& frame) {
  std::vector<float> xyz(3 * points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Vec3d p = frame.point(points[i]);
    for (int a = 0; a < 3; ++a) xyz[3 * i + static_cast<std::size_t>(a)] = static_cast<float>(p[a]);
  }
  return xyz;
}

}  // namespace

// ---- GpuExtinctionPyramid -------------------------------------------------------------------

struct GpuExtinctionPyramid::Impl {
  std::shared_ptr<GpuDevice> device;
  const ExtinctionPyramid* host = nullptr;
  GLuint program = 0;
  DeviceBuffer levels, infos;
  /// The frame of the pyramid's bounds: device positions and lengths are in it; the levels hold
  /// extinction per world unit, so the schedule's kappa carries the frame's scale.
  LocalFrame frame;
  /// A mesh's points, sent once and shared by every tracer on this pyramid across updates (the
  /// mesh is kept alive so that its address is never reused; re-sent if the frame moves).
  DeviceBuffer mesh_points;
  std::shared_ptr<const TetMesh> mesh_held;
  LocalFrame mesh_frame;
  std::vector<char> mesh_used;  ///< per point: does a tet use it

  /// Makes mesh_points hold `mesh`'s points; call with the context current.
  void hold_mesh(const GlApi& gl, const std::shared_ptr<const TetMesh>& mesh);
  std::size_t level_bytes = 0;
  double upload_ms = 0;
  std::uint64_t generation = 0;  ///< uploads so far: a tracer made before the last one is stale

  GpuDevice::Impl& dev() const { return device->impl(); }
  void upload(const ExtinctionPyramid& pyramid);
};

void GpuExtinctionPyramid::Impl::upload(const ExtinctionPyramid& pyramid) {
  require(pyramid.levels() >= 1, "GpuExtinctionPyramid: the extinction pyramid is empty");
  const auto t0 = Clock::now();
  const LocalFrame local = LocalFrame::of(pyramid.bounds());
  // The levels, then the unfiltered grid (ExtinctionPyramid::fine()) at index levels().
  const int count = pyramid.levels() + 1;
  auto level_at = [&](int l) -> const PyramidLevel& { return l < pyramid.levels() ? pyramid.level(l) : pyramid.fine(); };
  std::size_t values = 0;
  for (int l = 0; l < count; ++l) values += level_at(l).tau.size();
  require(values < (std::size_t{1} << 31), "GpuExtinctionPyramid: " + std::to_string(values) +
                                               " pyramid values exceed the shader's 32-bit indices");
  struct Info {
    GLint dims_offset[4];
    float lo[4];
    float inv_spacing[4];
  };
  std::vector<Info> info(static_cast<std::size_t>(count));
  std::size_t offset = 0;
  for (int l = 0; l < count; ++l) {
    const PyramidLevel& lev = level_at(l);
    Info& in = info[static_cast<std::size_t>(l)];
    for (int a = 0; a < 3; ++a) {
      in.dims_offset[a] = lev.dims[static_cast<std::size_t>(a)];
      in.lo[a] = static_cast<float>(local.point(lev.lo)[a]);
      in.inv_spacing[a] = static_cast<float>(1.0 / local.length(lev.spacing[a]));
    }
    in.dims_offset[3] = static_cast<GLint>(offset);
    in.lo[3] = lev.empty_beyond_nodes ? 1.0f : 0.0f;
    in.inv_spacing[3] = 0;
    offset += lev.tau.size();
  }
  CurrentContext current(dev());
  const GlApi& gl = current.gl();
  levels.reserve(gl, dev(), values * sizeof(float), "GpuExtinctionPyramid", "extinction pyramid levels");
  infos.reserve(gl, dev(), info.size() * sizeof(Info), "GpuExtinctionPyramid", "pyramid level headers");
  offset = 0;
  for (int l = 0; l < count; ++l) {
    const std::vector<float>& tau = level_at(l).tau;
    gl.NamedBufferSubData(levels.name, static_cast<GLintptr>(offset * sizeof(float)),
                          static_cast<GLsizeiptr>(tau.size() * sizeof(float)), tau.data());
    offset += tau.size();
  }
  gl.NamedBufferSubData(infos.name, 0, static_cast<GLsizeiptr>(info.size() * sizeof(Info)), info.data());
  host = &pyramid;
  ++generation;
  frame = local;
  level_bytes = values * sizeof(float);
  upload_ms = ms_since(t0);
}

void GpuExtinctionPyramid::Impl::hold_mesh(const GlApi& gl, const std::shared_ptr<const TetMesh>& mesh) {
  if (mesh_held == mesh && mesh_frame == frame) return;
  const std::vector<float> xyz = local_xyz(mesh->points, frame);
  mesh_held.reset();
  mesh_points.reserve(gl, dev(), xyz.size() * sizeof(float), "GpuExtinctionPyramid", "mesh points");
  gl.NamedBufferSubData(mesh_points.name, 0, static_cast<GLsizeiptr>(xyz.size() * sizeof(float)), xyz.data());
  mesh_used.assign(mesh->points.size(), 0);
  for (const auto& t : mesh->tets)
    for (auto v : t) mesh_used[static_cast<std::size_t>(v)] = 1;
  mesh_held = mesh;
  mesh_frame = frame;
}

GpuExtinctionPyramid::GpuExtinctionPyramid(std::shared_ptr<GpuDevice> device, const ExtinctionPyramid& pyramid)
    : m_impl(std::make_unique<Impl>()) {
  require(device != nullptr, "GpuExtinctionPyramid: device is null; expected GpuDevice::open()");
  Impl& m = *m_impl;
  m.device = std::move(device);
  if (m.dev().max_compute_storage_blocks < kBindingCount)
    throw Error(ErrorCode::backend_unavailable, "GPU backend: the device allows " +
                                                    std::to_string(m.dev().max_compute_storage_blocks) +
                                                    " storage buffers per compute shader; the cone tracer needs " +
                                                    std::to_string(static_cast<int>(kBindingCount)));
  {
    CurrentContext current(m.dev());
    m.program = gpu::compile_compute_program(current.gl(), gpu::kConeTraceShader, "cone-tracing");
  }
  try {
    m.upload(pyramid);
  } catch (...) {
    CurrentContext current(m.dev());
    m.levels.release(current.gl());
    m.infos.release(current.gl());
    current.gl().DeleteProgram(m.program);
    throw;
  }
}

GpuExtinctionPyramid::~GpuExtinctionPyramid() {
  try {
    CurrentContext current(m_impl->dev());
    const GlApi& gl = current.gl();
    m_impl->levels.release(gl);
    m_impl->infos.release(gl);
    m_impl->mesh_points.release(gl);
    gl.DeleteProgram(m_impl->program);
  } catch (...) {
    // The context is gone with the device; nothing is left to free.
  }
}

void GpuExtinctionPyramid::update(const ExtinctionPyramid& pyramid) { m_impl->upload(pyramid); }
const ExtinctionPyramid& GpuExtinctionPyramid::host() const { return *m_impl->host; }
std::size_t GpuExtinctionPyramid::level_bytes() const { return m_impl->level_bytes; }
double GpuExtinctionPyramid::upload_ms() const { return m_impl->upload_ms; }

// ---- GpuConeTracer --------------------------------------------------------------------------

struct GpuConeTracer::Impl {
  const GpuExtinctionPyramid* pyramid = nullptr;
  std::unique_ptr<ConeTracer> host;
  int schedule_count = 0;
  std::uint64_t generation = 0;  ///< the pyramid upload the schedule was made for
  mutable DeviceBuffer schedule, points, result, grid;  // points: those of transmittance()

  GpuExtinctionPyramid::Impl& pyr() const { return pyramid->impl(); }
  GpuDevice::Impl& dev() const { return pyr().dev(); }
  GLint uniform(const GlApi& gl, const char* name) const { return gl.GetUniformLocation(pyr().program, name); }
  /// Sets the cone and target uniforms (not the source).
  void set_cone_uniforms(const GlApi& gl, const ConeTarget& target) const;
  /// Runs `count` invocations of source `source` in chunks within the work-group limit.
  void dispatch(const GlApi& gl, int source, std::size_t count) const;
  void set_grid_uniforms(const GlApi& gl, const GpuPreIllumination& g) const;
  void bind_all(const GlApi& gl, GLuint points_buffer, GLuint result_buffer, GLuint grid_buffer) const;
  void check_errors(const GlApi& gl, const char* call) const;
  /// Throws Error(invalid_operation) when the pyramid was updated after this tracer was made.
  void require_current(const char* call) const {
    if (generation != pyr().generation)
      throw Error(ErrorCode::invalid_operation, std::string(call) +
                                                    ": the pyramid was updated after this tracer was made (its "
                                                    "schedule depends on the pyramid); make a new GpuConeTracer");
  }
};

void GpuConeTracer::Impl::set_cone_uniforms(const GlApi& gl, const ConeTarget& target) const {
  const GLuint p = pyr().program;
  const LocalFrame& frame = pyr().frame;
  auto u3 = [&](const char* name, const Vec3d& v) {
    gl.ProgramUniform3f(p, uniform(gl, name), static_cast<float>(v.x), static_cast<float>(v.y), static_cast<float>(v.z));
  };
  int kind = 0;
  Vec3d vector = frame.point(target.eye), spot_dir{0, 0, 1};
  double spot_cos = -2.0;  // lights everything
  if (target.kind == ConeTarget::Kind::light) {
    const ShadowLight& l = target.light;
    if (l.kind == ShadowLight::Kind::directional) {
      kind = 1;
      vector = -normalize(l.vector);  // any length: normalised in double
    } else {
      kind = l.kind == ShadowLight::Kind::point ? 2 : 3;
      vector = frame.point(l.vector);
      if (kind == 3) {
        const double sl = length(l.spot_direction);
        if (sl > 0) {
          spot_dir = l.spot_direction / sl;
          spot_cos = std::cos(l.spot_angle_deg * kPi / 180.0);
        } else {
          spot_cos = 2.0;  // shadow_transmittance: a spot without a direction lights nothing
        }
      }
    }
  }
  gl.ProgramUniform1i(p, uniform(gl, "u_target_kind"), kind);
  u3("u_target", vector);
  u3("u_spot_dir", spot_dir);
  gl.ProgramUniform1f(p, uniform(gl, "u_spot_cos"), static_cast<float>(spot_cos));
  gl.ProgramUniform1i(p, uniform(gl, "u_schedule_count"), schedule_count);
  gl.ProgramUniform1f(p, uniform(gl, "u_gap"), static_cast<float>(frame.length(host->gap())));
  gl.ProgramUniform1f(p, uniform(gl, "u_length"), static_cast<float>(frame.length(host->length())));
  gl.ProgramUniform1f(p, uniform(gl, "u_lateral3"), static_cast<float>(host->lateral_variance_ratio(3)));
  gl.ProgramUniform1f(p, uniform(gl, "u_lateral7"), static_cast<float>(host->lateral_variance_ratio(7)));
  // Sub-cone axes as ConeTracer's constructor makes them (thesis fig. 3.5 packings).
  const double tan_theta = std::tan(host->options().aperture_deg * kPi / 180.0);
  const double radius3 = 1.0 / (1.0 + 2.0 / std::sqrt(3.0)), offset3 = 1.0 - radius3, offset7 = 2.0 / 3.0;
  char name[16];
  for (int k = 0; k < 3; ++k) {
    const double phi = (30.0 + 120.0 * k) * kPi / 180.0;
    std::snprintf(name, sizeof name, "u_dir3[%d]", k);
    u3(name, normalize(Vec3d{tan_theta * offset3 * std::cos(phi), tan_theta * offset3 * std::sin(phi), 1.0}));
  }
  u3("u_dir7[0]", Vec3d{0, 0, 1});
  for (int j = 0; j < 6; ++j) {
    const double phi = 60.0 * j * kPi / 180.0;
    std::snprintf(name, sizeof name, "u_dir7[%d]", j + 1);
    u3(name, normalize(Vec3d{tan_theta * offset7 * std::cos(phi), tan_theta * offset7 * std::sin(phi), 1.0}));
  }
}

void GpuConeTracer::Impl::set_grid_uniforms(const GlApi& gl, const GpuPreIllumination& g) const {
  const GLuint p = pyr().program;
  const LocalFrame& frame = pyr().frame;
  const Vec3d lo = frame.point(g.lo), spacing = g.spacing / frame.scale;
  gl.ProgramUniform3f(p, uniform(gl, "u_grid_lo"), static_cast<float>(lo.x), static_cast<float>(lo.y), static_cast<float>(lo.z));
  gl.ProgramUniform3f(p, uniform(gl, "u_grid_spacing"), static_cast<float>(spacing.x), static_cast<float>(spacing.y),
                      static_cast<float>(spacing.z));
  gl.ProgramUniform1i(p, uniform(gl, "u_grid_nx"), g.dims[0]);
  gl.ProgramUniform1i(p, uniform(gl, "u_grid_ny"), g.dims[1]);
  gl.ProgramUniform1i(p, uniform(gl, "u_grid_nz"), g.dims[2]);
}

void GpuConeTracer::Impl::bind_all(const GlApi& gl, GLuint points_buffer, GLuint result_buffer,
                                   GLuint grid_buffer) const {
  gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, kLevels, pyr().levels.name);
  gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, kInfos, pyr().infos.name);
  gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, kSchedule, schedule.name);
  gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, kPoints, points_buffer);
  gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, kResult, result_buffer);
  gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, kGrid, grid_buffer);
}

void GpuConeTracer::Impl::dispatch(const GlApi& gl, int source, std::size_t count) const {
  const GLuint p = pyr().program;
  gl.ProgramUniform1i(p, uniform(gl, "u_source"), source);
  gpu::dispatch_chunked(gl, dev(), p, count, kLocalSize);
}

void GpuConeTracer::Impl::check_errors(const GlApi& gl, const char* call) const {
  const GLenum err = gl.GetError();
  if (err != GL_NO_ERROR)
    throw Error(err == GL_OUT_OF_MEMORY ? ErrorCode::out_of_memory : ErrorCode::internal_error,
                std::string(call) + ": OpenGL reported " + gpu::gl_error_text(err));
}

GpuConeTracer::GpuConeTracer(const GpuExtinctionPyramid& pyramid, const ConeOptions& options)
    : m_impl(std::make_unique<Impl>()) {
  Impl& m = *m_impl;
  m.pyramid = &pyramid;
  m.host = std::make_unique<ConeTracer>(pyramid.host(), options);
  m.generation = pyramid.impl().generation;
  const std::vector<ConeSample>& s = m.host->schedule();
  struct Entry {
    float distance_weight_kappa[4];
    GLint level_cones[4];
  };
  std::vector<Entry> entries(s.size());
  // Level and the level it blends toward; the unfiltered grid sits after the pyramid's levels.
  // Distances and weights in the pyramid's frame; kappa times its scale, for the levels' extinction
  // per world unit.
  const int fine = pyramid.host().levels();
  const LocalFrame& frame = m.pyr().frame;
  for (std::size_t i = 0; i < s.size(); ++i) {
    const bool below = s[i].level == kFineLevel;
    entries[i] = {{static_cast<float>(frame.length(s[i].distance)), static_cast<float>(frame.length(s[i].weight)),
                   static_cast<float>(s[i].kappa * frame.scale), static_cast<float>(s[i].blend)},
                  {below ? fine : s[i].level, s[i].cones, below ? 0 : s[i].level + 1, 0}};
  }
  m.schedule_count = static_cast<int>(s.size());
  CurrentContext current(m.dev());
  const GlApi& gl = current.gl();
  m.schedule.reserve(gl, m.dev(), entries.size() * sizeof(Entry), "GpuConeTracer", "cone schedule");
  if (!entries.empty())
    gl.NamedBufferSubData(m.schedule.name, 0, static_cast<GLsizeiptr>(entries.size() * sizeof(Entry)), entries.data());
}

GpuConeTracer::~GpuConeTracer() {
  try {
    CurrentContext current(m_impl->dev());
    const GlApi& gl = current.gl();
    for (DeviceBuffer* b : {&m_impl->schedule, &m_impl->points, &m_impl->result, &m_impl->grid}) b->release(gl);
  } catch (...) {
    // The context is gone with the device; nothing is left to free.
  }
}

const ConeTracer& GpuConeTracer::host() const { return *m_impl->host; }

std::vector<float> GpuConeTracer::transmittance(const ConeTarget& target, const std::vector<Vec3d>& points) const {
  const Impl& m = *m_impl;
  std::vector<float> out(points.size(), 1.0f);
  if (points.empty()) return out;
  require(points.size() < (std::size_t{1} << 31) / 3, "GpuConeTracer::transmittance: too many points for one call");
  CurrentContext current(m.dev());
  const GlApi& gl = current.gl();
  m.require_current("GpuConeTracer::transmittance");
  const std::vector<float> xyz = local_xyz(points, m.pyr().frame);
  m.points.reserve(gl, m.dev(), xyz.size() * sizeof(float), "GpuConeTracer", "query points");
  m.result.reserve(gl, m.dev(), out.size() * sizeof(float), "GpuConeTracer", "results");
  m.grid.reserve(gl, m.dev(), 16, "GpuConeTracer", "grid");  // bound but unread
  gl.NamedBufferSubData(m.points.name, 0, static_cast<GLsizeiptr>(xyz.size() * sizeof(float)), xyz.data());
  m.set_cone_uniforms(gl, target);
  m.bind_all(gl, m.points.name, m.result.name, m.grid.name);
  m.dispatch(gl, 0, points.size());
  gl.GetNamedBufferSubData(m.result.name, 0, static_cast<GLsizeiptr>(out.size() * sizeof(float)), out.data());
  m.check_errors(gl, "GpuConeTracer::transmittance");
  return out;
}

GpuPreIllumination GpuConeTracer::pre_illumination(const ConeTarget& target, const Bounds& bounds, int resolution) const {
  const Impl& m = *m_impl;
  const auto t0 = Clock::now();
  GpuPreIllumination g = gpu_pre_illumination_grid(bounds, resolution);
  CurrentContext current(m.dev());
  const GlApi& gl = current.gl();
  m.require_current("GpuConeTracer::pre_illumination");
  m.grid.reserve(gl, m.dev(), g.values.size() * sizeof(float), "GpuConeTracer", "pre-illumination grid");
  m.points.reserve(gl, m.dev(), 16, "GpuConeTracer", "query points");  // bound but unread
  m.set_cone_uniforms(gl, target);
  m.set_grid_uniforms(gl, g);
  m.bind_all(gl, m.points.name, m.grid.name, m.grid.name);  // the grid is written through Result
  m.dispatch(gl, 1, g.values.size());
  gl.GetNamedBufferSubData(m.grid.name, 0, static_cast<GLsizeiptr>(g.values.size() * sizeof(float)), g.values.data());
  m.check_errors(gl, "GpuConeTracer::pre_illumination");
  g.build_ms = ms_since(t0);
  return g;
}

std::vector<float> GpuConeTracer::at_mesh_points(const ConeTarget& target, const std::shared_ptr<const TetMesh>& mesh,
                                                 int volume_resolution) const {
  const Impl& m = *m_impl;
  require(mesh != nullptr, "GpuConeTracer::at_mesh_points: mesh is null");
  require(volume_resolution == 0 || volume_resolution >= 2,
          "GpuConeTracer::at_mesh_points: volume_resolution = " + std::to_string(volume_resolution) +
              "; expected 0 (at the points) or >= 2");
  const std::size_t n = mesh->points.size();
  std::vector<float> out(n, 1.0f);
  if (n == 0) return out;
  require(n < (std::size_t{1} << 31) / 3, "GpuConeTracer::at_mesh_points: too many points for one call");
  CurrentContext current(m.dev());
  const GlApi& gl = current.gl();
  m.require_current("GpuConeTracer::at_mesh_points");
  GpuExtinctionPyramid::Impl& pyr = m.pyr();
  pyr.hold_mesh(gl, mesh);  // sent once per mesh
  const GLuint points = pyr.mesh_points.name;
  m.result.reserve(gl, m.dev(), n * sizeof(float), "GpuConeTracer", "results");
  m.set_cone_uniforms(gl, target);
  if (volume_resolution > 0) {
    // Object space: the grid over the pyramid's bounds, then sampled at the points.
    GpuPreIllumination g = gpu_pre_illumination_grid(m.pyramid->host().bounds(), volume_resolution);
    m.grid.reserve(gl, m.dev(), g.values.size() * sizeof(float), "GpuConeTracer", "pre-illumination grid");
    m.set_grid_uniforms(gl, g);
    m.bind_all(gl, points, m.grid.name, m.grid.name);
    m.dispatch(gl, 1, g.values.size());
    m.bind_all(gl, points, m.result.name, m.grid.name);
    m.dispatch(gl, 2, n);
  } else {
    m.grid.reserve(gl, m.dev(), 16, "GpuConeTracer", "grid");  // bound but unread
    m.bind_all(gl, points, m.result.name, m.grid.name);
    m.dispatch(gl, 0, n);
  }
  gl.GetNamedBufferSubData(m.result.name, 0, static_cast<GLsizeiptr>(n * sizeof(float)), out.data());
  m.check_errors(gl, "GpuConeTracer::at_mesh_points");
  // A mesh's points that are in no tet take no part in rendering (evaluate_at_points gives them 1).
  for (std::size_t p = 0; p < n; ++p)
    if (!pyr.mesh_used[p]) out[p] = 1.0f;
  return out;
}

}  // namespace penumbra::render

// SPDX-License-Identifier: BSD-3-Clause
// render/src/gpu/gpu_ray_caster.cpp -- buffers, uniforms and dispatch of the ray-casting shader
#include "penumbra/render/gpu_ray_caster.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>

#include "gl_program.h"
#include "gpu_device_impl.h"
#include "gpu_mesh_layout.h"
#include "gpu_tf_layout.h"
#include "penumbra/core/error.h"
#include "ray_runs.h"
#include "render_inputs.h"
#include "shader_constants.h"

namespace penumbra::render {
namespace gpu {
extern const char* const kRayCastShader;  // render/shaders/ray_cast.comp, embedded at build time
}  // namespace gpu

namespace {

using gpu::CurrentContext;
using gpu::GlApi;

enum Binding : GLuint {
  kPoints, kTetVertices, kTetNext, kScalars, kTriangles, kNodes, kTf, kPixels, kLight, kRuns, kBindingCount
};
constexpr int kTile = 512;                     // pixels per side of one dispatch
constexpr int kRunsTile = 128;                 // the same with runs: 33 vec4 per pixel (ray_cast.comp)
constexpr std::size_t kRunSlots = 1 + 2 * shader::kMaxRayRuns;  // vec4 per pixel in the runs buffer
constexpr std::size_t kScalarBlock = 1 << 14;  // field values compared and re-sent per block

}  // namespace

struct GpuRayCaster::Impl {
  std::shared_ptr<GpuDevice> device;
  std::shared_ptr<const TetMesh> mesh;
  LocalFrame frame;    ///< of the mesh: every float32 position and length the shader sees
  double diagonal = 0;  ///< of the mesh's bounds, in the frame
  std::size_t triangle_count = 0;
  /// The boundary triangles in the mesh's boundary order, kept to rebuild the BVH for moved points.
  std::vector<std::array<std::int32_t, 4>> boundary;
  GLuint buffers[kBindingCount] = {};
  std::size_t capacity[kBindingCount] = {};
  /// What a per-frame buffer holds on the device, so that only changed blocks are sent again.
  struct Mirror {
    std::vector<float> values;
    bool valid = false;
  };
  Mirror scalars_held, light_held;
  std::size_t last_upload = 0;  ///< field bytes sent by the last render
  GpuMemoryStats stats;

  GpuDevice::Impl& dev() const { return device->impl(); }
  void allocate(const GlApi& gl, Binding b, std::size_t bytes, const void* data);
  /// Sends to buffer `b` the blocks of `values` that differ from `held`; returns the bytes sent.
  std::size_t upload_changed(const GlApi& gl, Binding b, const std::vector<float>& values, Mirror& held);
  GLint uniform(const GlApi& gl, const char* name) const { return gl.GetUniformLocation(dev().ray_cast_program, name); }
  /// Appends the runs of a w x h tile at (x0, y0) to each pixel's (depths back in world units).
  void read_runs(const GlApi& gl, int x0, int y0, int w, int h, int width, std::vector<float>& scratch,
                 detail::PixelRuns& runs) const;
};

void GpuRayCaster::Impl::read_runs(const GlApi& gl, int x0, int y0, int w, int h, int width, std::vector<float>& scratch,
                                   detail::PixelRuns& runs) const {
  const std::size_t slots = static_cast<std::size_t>(w) * h * kRunSlots;
  scratch.resize(slots * 4);
  gl.GetNamedBufferSubData(buffers[kRuns], 0, static_cast<GLsizeiptr>(slots * 16), scratch.data());
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const float* p = &scratch[(static_cast<std::size_t>(y) * w + x) * kRunSlots * 4];
      const int count = static_cast<int>(p[0]);
      if (count > shader::kMaxRayRuns)
        throw Error(ErrorCode::invalid_argument,
                    "GpuRayCaster::render: pixel (" + std::to_string(x0 + x) + ", " + std::to_string(y0 + y) + ") has " +
                        std::to_string(count) + " runs inside the mesh, more than the " +
                        std::to_string(shader::kMaxRayRuns) + " the GPU renderer returns per pixel; the CPU renderer returns them all");
      auto& pixel = runs[static_cast<std::size_t>(y0 + y) * width + x0 + x];
      for (int r = 0; r < count; ++r) {
        const float* depth = p + 4 * (1 + 2 * r);
        const float* rgba = depth + 4;
        RayRun run;
        run.entry_depth = static_cast<float>(depth[0] * frame.scale);
        run.exit_depth = static_cast<float>(depth[1] * frame.scale);
        for (int c = 0; c < 4; ++c) run.rgba[c] = rgba[c];
        pixel.push_back(run);
      }
    }
}

void GpuRayCaster::Impl::allocate(const GlApi& gl, Binding b, std::size_t bytes, const void* data) {
  bytes = std::max<std::size_t>(bytes, 16);  // an empty storage buffer cannot be bound
  const auto limit = static_cast<std::size_t>(dev().info.max_storage_block_bytes);
  if (limit > 0 && bytes > limit)
    throw Error(ErrorCode::out_of_memory, "GpuRayCaster: a storage buffer of " + gpu::mib(bytes) +
                                              " exceeds the device's GL_MAX_SHADER_STORAGE_BLOCK_SIZE of " + gpu::mib(limit) +
                                              " (mesh of " + std::to_string(mesh->tet_count()) + " tets)");
  while (gl.GetError() != GL_NO_ERROR) {
  }
  gl.NamedBufferData(buffers[b], static_cast<GLsizeiptr>(bytes), data, GL_STATIC_DRAW);
  const GLenum err = gl.GetError();
  if (err != GL_NO_ERROR)
    throw Error(err == GL_OUT_OF_MEMORY ? ErrorCode::out_of_memory : ErrorCode::internal_error,
                "GpuRayCaster: allocating " + gpu::mib(bytes) + " on the device failed with " + gpu::gl_error_text(err));
  capacity[b] = bytes;
}

std::size_t GpuRayCaster::Impl::upload_changed(const GlApi& gl, Binding binding, const std::vector<float>& values,
                                               Mirror& held) {
  const std::size_t n = values.size();
  if (!held.valid || held.values.size() != n) {
    gl.NamedBufferSubData(buffers[binding], 0, static_cast<GLsizeiptr>(n * sizeof(float)), values.data());
    held.values = values;
    held.valid = true;
    return n * sizeof(float);
  }
  // Bitwise comparison (NaN == NaN here); runs of changed blocks go in one call.
  std::size_t sent = 0;
  for (std::size_t b = 0; b < n;) {
    std::size_t e = std::min(n, b + kScalarBlock);
    if (std::memcmp(&values[b], &held.values[b], (e - b) * sizeof(float)) == 0) {
      b = e;
      continue;
    }
    while (e < n) {
      const std::size_t e2 = std::min(n, e + kScalarBlock);
      if (std::memcmp(&values[e], &held.values[e], (e2 - e) * sizeof(float)) == 0) break;
      e = e2;
    }
    gl.NamedBufferSubData(buffers[binding], static_cast<GLintptr>(b * sizeof(float)),
                          static_cast<GLsizeiptr>((e - b) * sizeof(float)), &values[b]);
    std::memcpy(&held.values[b], &values[b], (e - b) * sizeof(float));
    sent += (e - b) * sizeof(float);
    b = e;
  }
  return sent;
}

GpuRayCaster::GpuRayCaster(std::shared_ptr<GpuDevice> device, std::shared_ptr<const TetMesh> mesh)
    : m_impl(std::make_unique<Impl>()) {
  require(device != nullptr, "GpuRayCaster: device is null; expected GpuDevice::open()");
  require(mesh != nullptr, "GpuRayCaster: mesh is null; expected a prepared TetMesh");
  Impl& m = *m_impl;
  m.device = std::move(device);
  m.mesh = std::move(mesh);
  const gpu::GpuMeshLayout layout = gpu::build_gpu_mesh_layout(*m.mesh);
  m.frame = layout.frame;
  m.diagonal = layout.diagonal;
  m.triangle_count = layout.triangles.size();
  m.boundary = layout.boundary;

  GpuMemoryStats& s = m.stats;
  s.tets = layout.tet_vertices.size();
  s.points = m.mesh->points.size();
  s.boundary_triangles = layout.triangles.size();
  s.bvh_nodes = layout.nodes.size();
  s.geometry_bytes = layout.points.size() * sizeof(float) + layout.tet_vertices.size() * 16;
  s.adjacency_bytes = layout.tet_next.size() * 16;
  s.scalar_bytes = s.points * sizeof(float);
  s.acceleration_bytes = layout.triangles.size() * 16 + layout.nodes.size() * sizeof(gpu::BvhNode);
  s.frame_bytes = 0;
  const std::size_t needed = s.geometry_bytes + s.adjacency_bytes + s.scalar_bytes + s.acceleration_bytes;
  GpuDevice::Impl& d = m.dev();
  const std::string what = "GpuRayCaster: the mesh (" + std::to_string(s.tets) + " tets, " + std::to_string(s.points) +
                           " points) needs " + gpu::mib(needed) + " on the device";
  if (d.options.memory_limit_bytes > 0 && needed > d.options.memory_limit_bytes)
    throw Error(ErrorCode::out_of_memory, what + " but the configured limit is " + gpu::mib(d.options.memory_limit_bytes));
  if (d.info.free_memory_bytes >= 0 && needed > static_cast<std::size_t>(d.info.free_memory_bytes))
    throw Error(ErrorCode::out_of_memory, what + " but only " + gpu::mib(static_cast<std::size_t>(d.info.free_memory_bytes)) +
                                              " are free on " + d.info.gl_renderer);
  if (d.max_compute_storage_blocks < kBindingCount)
    throw Error(ErrorCode::backend_unavailable, "GPU backend: the device allows " +
                                                    std::to_string(d.max_compute_storage_blocks) +
                                                    " storage buffers per compute shader; " + std::to_string(static_cast<int>(kBindingCount)) +
                                                    " are needed");

  CurrentContext current(d);
  const GlApi& gl = current.gl();
  if (d.ray_cast_program == 0) d.ray_cast_program = gpu::compile_compute_program(gl, gpu::kRayCastShader, "ray-casting");
  gl.CreateBuffers(kBindingCount, m.buffers);
  try {
    m.allocate(gl, kPoints, layout.points.size() * sizeof(float), layout.points.data());
    m.allocate(gl, kTetVertices, layout.tet_vertices.size() * 16, layout.tet_vertices.data());
    m.allocate(gl, kTetNext, layout.tet_next.size() * 16, layout.tet_next.data());
    m.allocate(gl, kScalars, s.scalar_bytes, nullptr);
    m.allocate(gl, kTriangles, layout.triangles.size() * 16, layout.triangles.data());
    m.allocate(gl, kNodes, layout.nodes.size() * sizeof(gpu::BvhNode), layout.nodes.data());
  } catch (...) {
    gl.DeleteBuffers(kBindingCount, m.buffers);
    throw;
  }
  const std::vector<float> series = gpu::one_minus_z_series();
  gl.ProgramUniform1fv(d.ray_cast_program, m.uniform(gl, "u_series"), 64, series.data());
}

GpuRayCaster::~GpuRayCaster() {
  try {
    CurrentContext current(m_impl->dev());
    current.gl().DeleteBuffers(kBindingCount, m_impl->buffers);
  } catch (...) {
    // The context is gone with the device; nothing is left to free.
  }
}

Image GpuRayCaster::render(const std::vector<float>& scalars, const TransferFunction& tf, const Camera& camera,
                           const RenderOptions& options) {
  RenderOutput out;
  RenderOptions image_only = options;
  image_only.ray_runs = false;
  render(scalars, tf, camera, image_only, out);
  return std::move(out.image);
}

void GpuRayCaster::render(const std::vector<float>& scalars, const TransferFunction& tf, const Camera& camera,
                          const RenderOptions& options, RenderOutput& out) {
  Impl& m = *m_impl;
  detail::check_frame_inputs("GpuRayCaster::render", *m.mesh, scalars, tf, camera, options);
  const double opacity = options.early_termination_opacity;
  require(!options.shading.light_at, "GpuRayCaster::render: image-space light (Shading::light_at) is evaluated by the "
                                     "CPU ray caster only; give a per-point light_rgb instead");
  const gpu::GpuTfLayout table = gpu::build_gpu_tf_layout(tf, m.frame.scale);

  GpuDevice::Impl& d = m.dev();
  CurrentContext current(d);
  const GlApi& gl = current.gl();
  const GLuint program = d.ray_cast_program;
  m.last_upload = m.upload_changed(gl, kScalars, scalars, m.scalars_held);
  const std::size_t tf_bytes = table.data.size() * sizeof(float);
  if (m.capacity[kTf] < tf_bytes) m.allocate(gl, kTf, tf_bytes, nullptr);
  gl.NamedBufferSubData(m.buffers[kTf], 0, static_cast<GLsizeiptr>(tf_bytes), table.data.data());
  const bool with_runs = options.ray_runs;
  const int tile_side = with_runs ? kRunsTile : kTile;
  const int tile_w = std::min(camera.width, tile_side), tile_h = std::min(camera.height, tile_side);
  const std::size_t runs_bytes = with_runs ? static_cast<std::size_t>(tile_w) * tile_h * kRunSlots * 16 : 16;
  if (m.capacity[kRuns] < runs_bytes) m.allocate(gl, kRuns, runs_bytes, nullptr);
  const std::size_t tile_bytes = static_cast<std::size_t>(tile_w) * tile_h * 4 * sizeof(float);
  if (m.capacity[kPixels] < tile_bytes) m.allocate(gl, kPixels, tile_bytes, nullptr);
  const Shading& shading = options.shading;
  if (shading.model == LightingModel::light_volume) {
    // 12 B per point; the cameras of one step share it, so it is sent once per change.
    const std::size_t bytes = shading.light_rgb->size() * sizeof(float);
    if (m.capacity[kLight] < bytes) {
      m.allocate(gl, kLight, bytes, nullptr);
      m.light_held.valid = false;
    }
    m.upload_changed(gl, kLight, *shading.light_rgb, m.light_held);
  } else if (m.capacity[kLight] == 0) {
    m.allocate(gl, kLight, 16, nullptr);  // bound but unread
  }
  m.stats.frame_bytes = m.capacity[kTf] + m.capacity[kPixels] + m.capacity[kLight] + m.capacity[kRuns];
  for (GLuint b = 0; b < kBindingCount; ++b) gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, b, m.buffers[b]);

  // The camera of Camera::primary_ray, in the mesh's frame like the points.
  const Camera::Frame frame = camera.frame();
  const Vec3d &forward = frame.forward, &right = frame.right, &up = frame.up;
  const double half_h = frame.half_height, half_w = frame.half_width;
  const Vec3d eye = m.frame.point(camera.eye);
  const Bounds& bb = m.mesh->bounds;
  const double pad = 1e-9 * bb.diagonal();
  const Vec3d& o = camera.eye;
  const bool outside = o.x < bb.lo.x - pad || o.y < bb.lo.y - pad || o.z < bb.lo.z - pad || o.x > bb.hi.x + pad ||
                       o.y > bb.hi.y + pad || o.z > bb.hi.z + pad;
  // Depths are float32 relative to the eye: two faces' roundings of one exit depth differ by a
  // few units of 1e-7 * (distance + size), far below this slack.
  const double slack = 1e-5 * (m.diagonal + length(eye));
  auto u3 = [&](const char* name, const Vec3d& v) {
    gl.ProgramUniform3f(program, m.uniform(gl, name), static_cast<float>(v.x), static_cast<float>(v.y),
                        static_cast<float>(v.z));
  };
  u3("u_eye", eye);
  u3("u_forward", forward);
  u3("u_right", right);
  u3("u_up", up);
  gl.ProgramUniform2f(program, m.uniform(gl, "u_half_extent"), static_cast<float>(half_w), static_cast<float>(half_h));
  gl.ProgramUniform2i(program, m.uniform(gl, "u_image_size"), camera.width, camera.height);
  gl.ProgramUniform1i(program, m.uniform(gl, "u_eye_outside"), outside ? 1 : 0);
  gl.ProgramUniform1f(program, m.uniform(gl, "u_reentry_slack"), static_cast<float>(slack));
  gl.ProgramUniform1f(program, m.uniform(gl, "u_stop_transmittance"),
                      static_cast<float>(opacity >= 1.0 ? 0.0 : 1.0 - opacity));
  gl.ProgramUniform1i(program, m.uniform(gl, "u_tet_count"), static_cast<GLint>(m.stats.tets));
  gl.ProgramUniform1i(program, m.uniform(gl, "u_triangle_count"), static_cast<GLint>(m.triangle_count));
  gl.ProgramUniform1i(program, m.uniform(gl, "u_breakpoint_count"), table.breakpoint_count);
  const int model = shading.model == LightingModel::none ? 0 : (shading.model == LightingModel::phong ? 1 : 2);
  gl.ProgramUniform1i(program, m.uniform(gl, "u_shading"), model);
  gl.ProgramUniform1i(program, m.uniform(gl, "u_runs"), with_runs ? 1 : 0);
  gl.ProgramUniform4f(program, m.uniform(gl, "u_phong"), static_cast<float>(shading.ambient),
                      static_cast<float>(shading.diffuse), static_cast<float>(shading.specular),
                      static_cast<float>(shading.shininess));
  const double dl = length(shading.light_direction);
  gl.ProgramUniform1i(program, m.uniform(gl, "u_headlight"), dl > 0 ? 0 : 1);
  u3("u_to_light", dl > 0 ? shading.light_direction / dl : Vec3d{0, 0, 1});
  gl.UseProgram(program);

  Image& image = out.image;
  image = Image(camera.width, camera.height);
  const std::size_t pixels = with_runs ? static_cast<std::size_t>(camera.width) * camera.height : 0;
  detail::RunsBudget budget(options.ray_runs_memory_bytes, pixels);
  budget.check("GpuRayCaster::render");  // the per-pixel lists alone
  detail::PixelRuns runs(pixels);
  std::vector<float> tile(static_cast<std::size_t>(tile_w) * tile_h * 4), tile_runs;
  for (int y0 = 0; y0 < camera.height; y0 += tile_h)
    for (int x0 = 0; x0 < camera.width; x0 += tile_w) {
      const int w = std::min(tile_w, camera.width - x0), h = std::min(tile_h, camera.height - y0);
      gl.ProgramUniform2i(program, m.uniform(gl, "u_tile_origin"), x0, y0);
      gl.ProgramUniform2i(program, m.uniform(gl, "u_tile_size"), w, h);
      gl.DispatchCompute(static_cast<GLuint>((w + shader::kRayCastTile - 1) / shader::kRayCastTile),
                         static_cast<GLuint>((h + shader::kRayCastTile - 1) / shader::kRayCastTile), 1);
      gl.MemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
      gl.GetNamedBufferSubData(m.buffers[kPixels], 0, static_cast<GLsizeiptr>(static_cast<std::size_t>(w) * h * 16),
                               tile.data());
      for (int y = 0; y < h; ++y)
        std::memcpy(image.pixel(x0, y0 + y), &tile[static_cast<std::size_t>(y) * w * 4],
                    static_cast<std::size_t>(w) * 4 * sizeof(float));
      if (with_runs) {
        m.read_runs(gl, x0, y0, w, h, camera.width, tile_runs, runs);
        for (int y = y0; y < y0 + h; ++y) {
          const std::size_t row = static_cast<std::size_t>(y) * camera.width;
          budget.add(runs, row + x0, row + x0 + w);
        }
        budget.check("GpuRayCaster::render");
      }
    }
  gl.UseProgram(0);
  const GLenum err = gl.GetError();
  if (err != GL_NO_ERROR)
    throw Error(err == GL_OUT_OF_MEMORY ? ErrorCode::out_of_memory : ErrorCode::internal_error,
                "GpuRayCaster::render: OpenGL reported " + gpu::gl_error_text(err));
  out.runs = with_runs ? detail::flatten_runs(runs) : RayRuns{};
}

void GpuRayCaster::move_points(std::shared_ptr<const TetMesh> moved) {
  Impl& m = *m_impl;
  detail::require_same_connectivity("GpuRayCaster::move_points", *m.mesh, moved.get());
  gpu::GpuMeshLayout layout;
  layout.boundary = std::move(m.boundary);
  gpu::place_gpu_mesh_points(*moved, layout);
  m.boundary = std::move(layout.boundary);
  CurrentContext current(m.dev());
  const GlApi& gl = current.gl();
  // Same point and triangle counts, and a BVH of as many nodes (median splits of as many boxes):
  // the buffers keep their size.
  gl.NamedBufferSubData(m.buffers[kPoints], 0, static_cast<GLsizeiptr>(layout.points.size() * sizeof(float)),
                        layout.points.data());
  gl.NamedBufferSubData(m.buffers[kTriangles], 0, static_cast<GLsizeiptr>(layout.triangles.size() * 16),
                        layout.triangles.data());
  gl.NamedBufferSubData(m.buffers[kNodes], 0, static_cast<GLsizeiptr>(layout.nodes.size() * sizeof(gpu::BvhNode)),
                        layout.nodes.data());
  const GLenum err = gl.GetError();
  if (err != GL_NO_ERROR)
    throw Error(ErrorCode::internal_error, "GpuRayCaster::move_points: OpenGL reported " + gpu::gl_error_text(err));
  m.mesh = std::move(moved);
  m.frame = layout.frame;
  m.diagonal = layout.diagonal;
}

GpuMemoryStats GpuRayCaster::memory() const { return m_impl->stats; }
std::size_t GpuRayCaster::last_scalar_upload_bytes() const { return m_impl->last_upload; }
const TetMesh& GpuRayCaster::mesh() const { return *m_impl->mesh; }
const GpuDevice& GpuRayCaster::device() const { return *m_impl->device; }

}  // namespace penumbra::render

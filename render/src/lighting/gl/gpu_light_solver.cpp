// SPDX-License-Identifier: BSD-3-Clause
// render/src/lighting/gl/gpu_light_solver.cpp -- buffers and dispatches of the light-volume kernels
#include "../gpu_light_solver.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <string>

#include "../../gpu/gl_program.h"
#include "../../gpu/gpu_device_impl.h"
#include "../light_scattering.h"
#include "penumbra/core/error.h"
#include "penumbra/render/gpu_ray_caster.h"
#include "shader_constants.h"

namespace penumbra::render {
namespace gpu {
// render/shaders/light_*.comp, embedded at build time
extern const char* const kLightLevel0Shader;
extern const char* const kLightLevel1Shader;
extern const char* const kLightScatterShader;
}  // namespace gpu

namespace lighting {
namespace {

using gpu::CurrentContext;
using gpu::GlApi;

constexpr GLuint kGroupSize = shader::kLightGroup;  // local_size_x of every kernel
constexpr int kScatterBatch = 8;       // Jacobi iterations between two residual read-backs
constexpr GLuint kLevel1Bindings = 13;  // storage blocks of light_level1.comp, the most of the three

/// One storage buffer, grown on demand.
struct Buffer {
  GLuint id = 0;
  std::size_t bytes = 0;
};

std::int32_t to_int32(std::int64_t v, const char* what) {
  if (v > std::numeric_limits<std::int32_t>::max())
    throw Error(ErrorCode::out_of_memory, std::string("GPU light volume: ") + what + " (" + std::to_string(v) +
                                              ") exceeds the 32-bit indices of the kernels");
  return static_cast<std::int32_t>(v);
}

}  // namespace

struct GpuLightBuffers {
  std::shared_ptr<GpuDevice> keep_device;  // the buffers live in its context
  GpuDevice::Impl* device = nullptr;
  Buffer rho0, rho1, next, order, start_tet;
  std::vector<std::size_t> group_end;
  std::size_t ordered = 0;
  ~GpuLightBuffers() {
    if (device == nullptr) return;
    try {
      CurrentContext current(*device);
      for (Buffer* b : {&rho0, &rho1, &next, &order, &start_tet})
        if (b->id) current.gl().DeleteBuffers(1, &b->id);
    } catch (...) {
      // The context went with the device; nothing is left to free.
    }
  }
};

struct GpuLightSolver::Impl {
  std::shared_ptr<GpuDevice> device;
  const TetMesh* mesh = nullptr;
  std::size_t points = 0;
  // The kernels work in the mesh's local frame (float32): positions, lengths and the extinction
  // table; the level-0 grid holds extinction per world unit, so the level-0 kernel gets the
  // frame's scale in its sigma_a.
  LocalFrame frame;
  GLuint level0_program = 0, level1_program = 0, scatter_program = 0;
  // Mesh (uploaded once).
  Buffer mesh_points, tets, neighbors, incidence, edges, weights;
  // Field and grid.
  Buffer point_scalars, params, grid_tau, grid_mask, counters;
  std::vector<Bounds> occluders;      // in world units
  std::vector<float> occluder_boxes;  // lo.xyz, hi.xyz per box, in the frame
  int breakpoint_count = 0, occluder_offset = 0;
  std::array<int, 3> dims{0, 0, 0};
  Vec3d grid_lo, spacing;  // of the level-0 grid, in world units
  // Scattering: source and two iterates (ping-pong).
  Buffer pre, iterate[2];
  int current = 0;
  int scatter_iterations = 0;  // since the source was set: Chebyshev's omega depends on it
  std::array<double, 3> omega{1.0, 1.0, 1.0};

  GpuDevice::Impl& dev() const { return device->impl(); }
  /// xyz in the frame and the longest incident edge (in the frame) per point.
  std::vector<float> point_layout(const Level1Topology& topology) const {
    std::vector<float> pts(4 * points);
    for (std::size_t p = 0; p < points; ++p) {
      const Vec3d r = frame.point(mesh->points[p]);
      pts[4 * p] = static_cast<float>(r.x);
      pts[4 * p + 1] = static_cast<float>(r.y);
      pts[4 * p + 2] = static_cast<float>(r.z);
      pts[4 * p + 3] = p < topology.longest_edge.size() ? static_cast<float>(frame.length(topology.longest_edge[p])) : 0.0f;
    }
    return pts;
  }
  void place_occluders() {
    occluder_boxes.clear();
    for (const Bounds& b : occluders) {
      const Vec3d lo = frame.point(b.lo), hi = frame.point(b.hi);
      for (double v : {lo.x, lo.y, lo.z, hi.x, hi.y, hi.z}) occluder_boxes.push_back(static_cast<float>(v));
    }
  }

  void allocate(const GlApi& gl, Buffer& b, std::size_t bytes, const void* data) {
    bytes = std::max<std::size_t>(bytes, 16);  // an empty storage buffer cannot be bound
    const auto limit = static_cast<std::size_t>(dev().info.max_storage_block_bytes);
    if (limit > 0 && bytes > limit)
      throw Error(ErrorCode::out_of_memory, "GPU light volume: a storage buffer of " + gpu::mib(bytes) +
                                                " exceeds the device's GL_MAX_SHADER_STORAGE_BLOCK_SIZE of " + gpu::mib(limit));
    if (b.id == 0) gl.CreateBuffers(1, &b.id);
    while (gl.GetError() != GL_NO_ERROR) {
    }
    gl.NamedBufferData(b.id, static_cast<GLsizeiptr>(bytes), data, GL_DYNAMIC_DRAW);
    const GLenum err = gl.GetError();
    if (err != GL_NO_ERROR)
      throw Error(err == GL_OUT_OF_MEMORY ? ErrorCode::out_of_memory : ErrorCode::internal_error,
                  "GPU light volume: allocating " + gpu::mib(bytes) + " on the device failed with " + gpu::gl_error_text(err));
    b.bytes = bytes;
  }
  template <class T>
  void upload(const GlApi& gl, Buffer& b, const std::vector<T>& values) {
    const std::size_t bytes = values.size() * sizeof(T);
    if (b.id == 0 || b.bytes < bytes) {
      allocate(gl, b, bytes, nullptr);
    }
    if (bytes > 0) gl.NamedBufferSubData(b.id, 0, static_cast<GLsizeiptr>(bytes), values.data());
  }
  template <class T>
  void download(const GlApi& gl, const Buffer& b, std::vector<T>& values, std::size_t count) {
    values.resize(count);
    if (count == 0) return;
    gl.MemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    gl.GetNamedBufferSubData(b.id, 0, static_cast<GLsizeiptr>(count * sizeof(T)), values.data());
  }
  static void bind(const GlApi& gl, GLuint binding, const Buffer& b) {
    gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, binding, b.id);
  }
  /// Invocations 0 .. n-1 of a kernel with local size kGroupSize, split over y beyond the
  /// device's group-count limit (the kernels fold y back into one index).
  void dispatch(const GlApi& gl, std::size_t n) const {
    if (n == 0) return;
    const std::size_t groups = (n + kGroupSize - 1) / kGroupSize;
    const std::size_t max_x = static_cast<std::size_t>(std::max<std::int64_t>(1, dev().max_work_group_count_x));
    const std::size_t x = std::min(groups, max_x), y = (groups + x - 1) / x;
    gl.DispatchCompute(static_cast<GLuint>(x), static_cast<GLuint>(y), 1);
    gl.MemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
  }
  static GLint loc(const GlApi& gl, GLuint program, const char* name) { return gl.GetUniformLocation(program, name); }
  static void set1i(const GlApi& gl, GLuint program, const char* name, long long v) {
    gl.ProgramUniform1i(program, loc(gl, program, name), static_cast<GLint>(v));
  }
  static void set1f(const GlApi& gl, GLuint program, const char* name, double v) {
    gl.ProgramUniform1f(program, loc(gl, program, name), static_cast<float>(v));
  }
  static void set3f(const GlApi& gl, GLuint program, const char* name, const Vec3d& v) {
    gl.ProgramUniform3f(program, loc(gl, program, name), static_cast<float>(v.x), static_cast<float>(v.y),
                        static_cast<float>(v.z));
  }
  static void set3i(const GlApi& gl, GLuint program, const char* name, const std::array<int, 3>& v) {
    gl.ProgramUniform3i(program, loc(gl, program, name), v[0], v[1], v[2]);
  }
  void clear_counters(const GlApi& gl) {
    const std::vector<std::uint32_t> zeros(kScatterBatch, 0u);
    gl.NamedBufferSubData(counters.id, 0, static_cast<GLsizeiptr>(zeros.size() * 4), zeros.data());
  }
  void release(const GlApi& gl) {
    Impl& m = *this;
    for (Buffer* b : {&m.mesh_points, &m.tets, &m.neighbors, &m.incidence, &m.edges, &m.weights, &m.point_scalars,
                      &m.params, &m.grid_tau, &m.grid_mask, &m.counters, &m.pre, &m.iterate[0], &m.iterate[1]})
      if (b->id) {
        gl.DeleteBuffers(1, &b->id);
        *b = Buffer{};
      }
    for (GLuint* p : {&m.level0_program, &m.level1_program, &m.scatter_program})
      if (*p) {
        gl.DeleteProgram(*p);
        *p = 0;
      }
  }
  static void check_errors(const GlApi& gl, const char* where) {
    const GLenum err = gl.GetError();
    if (err != GL_NO_ERROR)
      throw Error(err == GL_OUT_OF_MEMORY ? ErrorCode::out_of_memory : ErrorCode::internal_error,
                  std::string("GPU light volume: ") + where + ": OpenGL reported " + gpu::gl_error_text(err));
  }
};

GpuLightSolver::GpuLightSolver(std::shared_ptr<GpuDevice> device, const TetMesh& mesh, const Level1Topology& topology,
                               const std::vector<float>& scatter_weights, const std::vector<Bounds>& occluders)
    : m_impl(std::make_unique<Impl>()) {
  require(device != nullptr, "GPU light volume: device is null; expected GpuDevice::open()");
  Impl& m = *m_impl;
  m.device = std::move(device);
  m.mesh = &mesh;
  m.points = mesh.points.size();
  m.frame = mesh.frame;
  GpuDevice::Impl& d = m.dev();
  if (d.max_compute_storage_blocks < static_cast<std::int64_t>(kLevel1Bindings))
    throw Error(ErrorCode::backend_unavailable, "GPU light volume: the device allows " +
                                                    std::to_string(d.max_compute_storage_blocks) +
                                                    " storage buffers per compute shader; " +
                                                    std::to_string(kLevel1Bindings) + " are needed");
  m.occluders = occluders;
  m.place_occluders();

  // Mesh layout: float32 xyz in the frame with the longest incident edge in w (point_layout); tet
  // vertices and neighbours as ivec4; a point's incident tets (4 tet + local) and edge
  // neighbours behind their offsets (offsets shifted past the offset table itself).
  const std::size_t np = m.points;
  const std::vector<float> pts = m.point_layout(topology);
  // Tets as the CPU walk's records (in its Morton order, neighbours as record << 2 | face), and
  // each point's star as (record << 2 | local index, the opposite face's vertices outward).
  const auto& walk = topology.walk_tets;
  std::vector<std::int32_t> tv(4 * walk.size()), nb(4 * walk.size());
  for (std::size_t t = 0; t < walk.size(); ++t)
    for (int k = 0; k < 4; ++k) {
      tv[4 * t + k] = walk[t].v[k];
      nb[4 * t + k] = walk[t].next[k];
    }
  to_int32(static_cast<std::int64_t>(np + 1 + 4 * topology.star.size()), "the point-to-tet table");
  to_int32(static_cast<std::int64_t>(np + 1 + topology.edge_ids.size()), "the edge table");
  to_int32(static_cast<std::int64_t>(4 * mesh.tets.size()), "the tet count times 4");
  std::vector<std::int32_t> inc(np + 1 + 4 * topology.star.size()), edges(np + 1 + topology.edge_ids.size());
  for (std::size_t p = 0; p <= np; ++p) {
    inc[p] = static_cast<std::int32_t>(np + 1 + 4 * static_cast<std::size_t>(topology.tet_offsets[p]));
    edges[p] = static_cast<std::int32_t>(np + 1 + static_cast<std::size_t>(topology.edge_offsets[p]));
  }
  for (std::size_t s = 0; s < topology.star.size(); ++s) {
    const StarFace& f = topology.star[s];
    std::int32_t* e = &inc[np + 1 + 4 * s];
    e[0] = f.record;
    for (int j = 0; j < 3; ++j) e[1 + j] = f.v[j];
  }
  std::copy(topology.edge_ids.begin(), topology.edge_ids.end(), edges.begin() + static_cast<std::ptrdiff_t>(np + 1));

  // Mesh, topology and weights, the scattering's three colour fields (12 B per point each)
  // and one light's level-1 buffers (value, next, order, start tet: 16 B per point); the
  // level-0 grid and further lights come on top.
  const std::size_t needed = pts.size() * 4 + tv.size() * 8 + inc.size() * 4 + edges.size() * 4 +
                             scatter_weights.size() * 4 + np * (3 * 12 + 16);
  const std::string what = "GPU light volume: the mesh (" + std::to_string(mesh.tets.size()) + " tets, " +
                           std::to_string(np) + " points) needs " + gpu::mib(needed) + " on the device";
  if (d.options.memory_limit_bytes > 0 && needed > d.options.memory_limit_bytes)
    throw Error(ErrorCode::out_of_memory, what + " but the configured limit is " + gpu::mib(d.options.memory_limit_bytes));
  if (d.info.free_memory_bytes >= 0 && needed > static_cast<std::size_t>(d.info.free_memory_bytes))
    throw Error(ErrorCode::out_of_memory, what + " but only " + gpu::mib(static_cast<std::size_t>(d.info.free_memory_bytes)) +
                                              " are free on " + d.info.gl_renderer);

  CurrentContext current(d);
  const GlApi& gl = current.gl();
  try {
    m.level0_program = gpu::compile_compute_program(gl, gpu::kLightLevel0Shader, "light-volume level-0");
    m.level1_program = gpu::compile_compute_program(gl, gpu::kLightLevel1Shader, "light-volume level-1");
    m.scatter_program = gpu::compile_compute_program(gl, gpu::kLightScatterShader, "light-volume scattering");
    m.upload(gl, m.mesh_points, pts);
    m.upload(gl, m.tets, tv);
    m.upload(gl, m.neighbors, nb);
    m.upload(gl, m.incidence, inc);
    m.upload(gl, m.edges, edges);
    m.upload(gl, m.weights, scatter_weights);
    m.allocate(gl, m.counters, 4 * kScatterBatch, nullptr);
    Impl::check_errors(gl, "uploading the mesh");
  } catch (...) {
    m.release(gl);
    throw;
  }
}

GpuLightSolver::~GpuLightSolver() {
  try {
    CurrentContext current(m_impl->dev());
    m_impl->release(current.gl());
  } catch (...) {
    // The context went with the device; nothing is left to free.
  }
}

void GpuLightSolver::move_points(const TetMesh& mesh, const Level1Topology& topology,
                                 const std::vector<float>& scatter_weights) {
  Impl& m = *m_impl;
  require(mesh.points.size() == m.points, "GPU light volume: the moved mesh has " + std::to_string(mesh.points.size()) +
                                              " points; the solver's has " + std::to_string(m.points));
  m.mesh = &mesh;
  m.frame = mesh.frame;
  m.place_occluders();
  const std::vector<float> pts = m.point_layout(topology);
  CurrentContext current(m.dev());
  const GlApi& gl = current.gl();
  m.upload(gl, m.mesh_points, pts);
  m.upload(gl, m.weights, scatter_weights);
  Impl::check_errors(gl, "uploading the moved points");
}

void GpuLightSolver::set_grid(const Level0Grid& grid) {
  Impl& m = *m_impl;
  m.dims = grid.dims();
  m.grid_lo = grid.lo();
  m.spacing = grid.spacing();
  const auto& mask = grid.mask();
  std::vector<std::uint32_t> packed((mask.size() + 3) / 4, 0u);
  for (std::size_t i = 0; i < mask.size(); ++i)
    packed[i / 4] |= static_cast<std::uint32_t>(mask[i]) << (8 * (i % 4));
  CurrentContext current(m.dev());
  const GlApi& gl = current.gl();
  m.upload(gl, m.grid_mask, packed);
  m.upload(gl, m.grid_tau, grid.tau());
  Impl::check_errors(gl, "uploading the level-0 grid");
}

void GpuLightSolver::set_field(const Level0Grid& grid, const Level1Field& field) {
  Impl& m = *m_impl;
  // The CPU walk's extinction table, piece by piece: tau linear in s between breakpoints.
  const ExtinctionTable& table = field.table;
  const std::vector<double>& x = table.breakpoints();
  const std::size_t n = x.size();
  std::vector<float> params(3 * n + 2);
  for (std::size_t i = 0; i < n; ++i) params[i] = static_cast<float>(x[i]);
  for (std::size_t p = 0; p <= n; ++p) {
    params[n + p] = static_cast<float>(m.frame.extinction(table.intercept(p)));
    params[2 * n + 1 + p] = static_cast<float>(m.frame.extinction(table.slope(p)));
  }
  m.breakpoint_count = static_cast<int>(n);
  m.occluder_offset = static_cast<int>(params.size());
  params.insert(params.end(), m.occluder_boxes.begin(), m.occluder_boxes.end());
  CurrentContext current(m.dev());
  const GlApi& gl = current.gl();
  m.upload(gl, m.point_scalars, field.scalars);  // NaN: no data
  m.upload(gl, m.params, params);
  m.upload(gl, m.grid_tau, grid.tau());
  Impl::check_errors(gl, "uploading the field");
}

std::shared_ptr<GpuLightBuffers> GpuLightSolver::new_light() {
  auto b = std::make_shared<GpuLightBuffers>();
  b->device = &m_impl->dev();
  b->keep_device = m_impl->device;
  return b;
}

void GpuLightSolver::solve_level0(GpuLightBuffers& buffers, const Light& light, double sigma_a, std::vector<float>& rho0) {
  Impl& m = *m_impl;
  const auto& dims = m.dims;
  const std::size_t nodes = static_cast<std::size_t>(dims[0]) * dims[1] * dims[2];
  const Vec3d h = m.spacing;
  std::array<int, 3> centre{};
  Vec3d w_dir{0, 0, 0}, light_rel{0, 0, 0};
  double ds_dir = 0;
  const bool point = light.kind == Light::Kind::point;
  if (!point) {
    // As level0_sweep.cpp: the octant's corner just outside the grid is the light's node.
    const Vec3d u = normalize(light.vector);
    double sum = 0;
    for (int a = 0; a < 3; ++a) {
      centre[a] = u[a] >= 0 ? -1 : dims[a];
      w_dir[a] = std::fabs(u[a]) / h[a];
      sum += w_dir[a];
    }
    w_dir = w_dir / sum;
    ds_dir = 1.0 / sum;
  } else {
    const Vec3d& lo = m.grid_lo;
    for (int a = 0; a < 3; ++a)
      centre[a] = static_cast<int>(std::clamp(std::lround((light.vector[a] - lo[a]) / h[a]), -1L, static_cast<long>(dims[a])));
    light_rel = (light.vector - lo) / m.frame.scale;
  }
  // Wavefronts m = |i - c_i| + |j - c_j| + |k - c_k| from the nearest node to the farthest.
  int level_lo = 0, level_hi = 0;
  for (int a = 0; a < 3; ++a) {
    level_lo += centre[a] < 0 ? -centre[a] : (centre[a] >= dims[a] ? centre[a] - dims[a] + 1 : 0);
    level_hi += std::max(std::abs(centre[a]), std::abs(dims[a] - 1 - centre[a]));
  }
  CurrentContext current(m.dev());
  const GlApi& gl = current.gl();
  const GLuint prog = m.level0_program;
  if (buffers.rho0.bytes < nodes * sizeof(float)) m.allocate(gl, buffers.rho0, nodes * sizeof(float), nullptr);
  Impl::bind(gl, 0, m.grid_tau);
  Impl::bind(gl, 1, m.grid_mask);
  Impl::bind(gl, 2, buffers.rho0);
  Impl::set3i(gl, prog, "u_dims", dims);
  Impl::set3i(gl, prog, "u_centre", centre);
  Impl::set1i(gl, prog, "u_point", point ? 1 : 0);
  Impl::set3f(gl, prog, "u_spacing", h / m.frame.scale);
  Impl::set3f(gl, prog, "u_light", light_rel);
  Impl::set3f(gl, prog, "u_w_dir", w_dir);
  Impl::set1f(gl, prog, "u_ds_dir", m.frame.length(ds_dir));
  Impl::set1f(gl, prog, "u_sigma_a", m.frame.extinction(sigma_a));  // the grid's tau is per world unit
  gl.UseProgram(prog);
  const GLint level = Impl::loc(gl, prog, "u_level");
  const std::size_t rows = static_cast<std::size_t>(dims[1]) * dims[2];
  for (int lv = level_lo; lv <= level_hi; ++lv) {
    gl.ProgramUniform1i(prog, level, lv);
    m.dispatch(gl, rows);
  }
  gl.UseProgram(0);
  m.download(gl, buffers.rho0, rho0, nodes);
  Impl::check_errors(gl, "level-0 sweep");
}

void GpuLightSolver::set_order(GpuLightBuffers& buffers, const VertexOrder& order) {
  Impl& m = *m_impl;
  std::vector<std::int32_t> packed(order.vertices.begin(), order.vertices.end());
  packed.insert(packed.end(), order.group_of.begin(), order.group_of.end());
  buffers.group_end = order.group_end;
  buffers.ordered = order.vertices.size();
  const std::vector<std::int32_t> unknown(m.points, -1);  // start tets: found again on first use
  CurrentContext current(m.dev());
  const GlApi& gl = current.gl();
  m.upload(gl, buffers.order, packed);
  m.upload(gl, buffers.start_tet, unknown);
  Impl::check_errors(gl, "uploading the vertex order");
}

void GpuLightSolver::set_rho1(GpuLightBuffers& buffers, const std::vector<float>& rho1) {
  Impl& m = *m_impl;
  CurrentContext current(m.dev());
  const GlApi& gl = current.gl();
  m.upload(gl, buffers.rho1, rho1);
  m.upload(gl, buffers.next, rho1);
  Impl::check_errors(gl, "uploading level-1 values");
}

double GpuLightSolver::level1_pass(GpuLightBuffers& buffers, const Light& light, const Level1Context& ctx,
                                   std::vector<float>& rho1, std::size_t& lost) {
  Impl& m = *m_impl;
  const bool point = light.kind == Light::Kind::point;
  CurrentContext current(m.dev());
  const GlApi& gl = current.gl();
  const GLuint prog = m.level1_program;
  const Buffer* bindings[kLevel1Bindings] = {&m.mesh_points, &m.tets,      &m.neighbors,    &m.point_scalars,
                                             &m.incidence,   &m.params,    &m.grid_mask,    &buffers.rho0,
                                             &buffers.rho1,  &buffers.next, &buffers.order, &buffers.start_tet,
                                             &m.counters};
  for (GLuint b = 0; b < kLevel1Bindings; ++b) Impl::bind(gl, b, *bindings[b]);
  m.clear_counters(gl);
  Impl::set1i(gl, prog, "u_group_offset", static_cast<long long>(buffers.ordered));
  Impl::set1i(gl, prog, "u_point", point ? 1 : 0);
  Impl::set3f(gl, prog, "u_light", point ? m.frame.point(light.vector) : normalize(light.vector));
  Impl::set1f(gl, prog, "u_sigma_a", ctx.sigma_a);
  Impl::set1f(gl, prog, "u_step", m.frame.length(ctx.step));
  Impl::set1i(gl, prog, "u_adaptive", ctx.adaptive ? 1 : 0);
  Impl::set3f(gl, prog, "u_box_lo", m.frame.point(m.mesh->bounds.lo));
  Impl::set3f(gl, prog, "u_box_hi", m.frame.point(m.mesh->bounds.hi));
  Impl::set3i(gl, prog, "u_dims", m.dims);
  Impl::set3f(gl, prog, "u_grid_lo", m.frame.point(m.grid_lo));
  Impl::set3f(gl, prog, "u_spacing", m.spacing / m.frame.scale);
  Impl::set1i(gl, prog, "u_breakpoints", m.breakpoint_count);
  Impl::set1i(gl, prog, "u_occluders", static_cast<long long>(m.occluder_boxes.size() / 6));
  Impl::set1i(gl, prog, "u_occluder_offset", m.occluder_offset);
  Impl::set1i(gl, prog, "u_mode", 0);
  gl.UseProgram(prog);
  const GLint group = Impl::loc(gl, prog, "u_group"), begin = Impl::loc(gl, prog, "u_begin"),
              count = Impl::loc(gl, prog, "u_count");
  std::size_t first = 0;
  for (std::size_t g = 0; g < buffers.group_end.size(); ++g) {
    const std::size_t end = buffers.group_end[g];
    gl.ProgramUniform1i(prog, group, static_cast<GLint>(g));
    gl.ProgramUniform1i(prog, begin, static_cast<GLint>(first));
    gl.ProgramUniform1i(prog, count, static_cast<GLint>(end - first));
    m.dispatch(gl, end - first);
    first = end;
  }
  Impl::set1i(gl, prog, "u_mode", 1);
  gl.ProgramUniform1i(prog, count, static_cast<GLint>(buffers.ordered));
  m.dispatch(gl, buffers.ordered);
  gl.UseProgram(0);
  std::vector<std::uint32_t> result;
  m.download(gl, m.counters, result, 2);
  m.download(gl, buffers.rho1, rho1, m.points);
  Impl::check_errors(gl, "level-1 pass");
  float residual = 0.0f;
  std::memcpy(&residual, &result[0], sizeof residual);
  lost += result[1];
  return residual;
}

void GpuLightSolver::set_scatter_source(const std::vector<float>& pre, const std::vector<float>& start) {
  Impl& m = *m_impl;
  CurrentContext current(m.dev());
  const GlApi& gl = current.gl();
  m.upload(gl, m.pre, pre);
  m.current = 0;
  m.scatter_iterations = 0;
  m.upload(gl, m.iterate[0], start);
  if (m.iterate[1].bytes < start.size() * sizeof(float)) m.allocate(gl, m.iterate[1], start.size() * sizeof(float), nullptr);
  Impl::check_errors(gl, "uploading the scattering source");
}

int GpuLightSolver::scatter(int max_iterations, double tolerance, const std::array<double, 3>& sigma_s,
                            double& residual) {
  Impl& m = *m_impl;
  CurrentContext current(m.dev());
  const GlApi& gl = current.gl();
  const GLuint prog = m.scatter_program;
  Impl::bind(gl, 0, m.edges);
  Impl::bind(gl, 1, m.weights);
  Impl::bind(gl, 2, m.pre);
  Impl::bind(gl, 5, m.counters);
  Impl::set1i(gl, prog, "u_points", static_cast<long long>(m.points));
  Impl::set3f(gl, prog, "u_sigma_s", {sigma_s[0], sigma_s[1], sigma_s[2]});
  const GLint slot = Impl::loc(gl, prog, "u_slot"), omega = Impl::loc(gl, prog, "u_omega"),
              first = Impl::loc(gl, prog, "u_first");
  gl.UseProgram(prog);
  const int batch = std::clamp(max_iterations, 1, kScatterBatch);
  m.clear_counters(gl);
  for (int i = 0; i < batch; ++i) {
    Impl::bind(gl, 3, m.iterate[m.current]);
    Impl::bind(gl, 4, m.iterate[1 - m.current]);
    gl.ProgramUniform1i(prog, slot, i);
    const int k = m.scatter_iterations++;
    chebyshev_weights(k, sigma_s, m.omega);
    gl.ProgramUniform3f(prog, omega, static_cast<GLfloat>(m.omega[0]), static_cast<GLfloat>(m.omega[1]),
                        static_cast<GLfloat>(m.omega[2]));
    gl.ProgramUniform1i(prog, first, k == 0 ? 1 : 0);
    m.dispatch(gl, m.points);
    m.current = 1 - m.current;
  }
  gl.UseProgram(0);
  std::vector<std::uint32_t> changes;
  m.download(gl, m.counters, changes, static_cast<std::size_t>(batch));
  Impl::check_errors(gl, "scattering");
  for (int i = 0; i < batch; ++i) {
    float change = 0.0f;
    std::memcpy(&change, &changes[static_cast<std::size_t>(i)], sizeof change);
    residual = change;
    if (change <= tolerance) break;  // the batch's later iterations only refine further
  }
  return batch;
}

void GpuLightSolver::read_scatter(std::vector<float>& rgb) {
  Impl& m = *m_impl;
  CurrentContext current(m.dev());
  const GlApi& gl = current.gl();
  m.download(gl, m.iterate[m.current], rgb, 3 * m.points);
  Impl::check_errors(gl, "reading the scattered light");
}

}  // namespace lighting
}  // namespace penumbra::render

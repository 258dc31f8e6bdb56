// SPDX-License-Identifier: BSD-3-Clause
// render/src/occlusion/gl/gpu_pyramid_build.cpp -- the extinction pyramid filtered on the device
// (render/shaders/pyramid_filter.comp), level by level as ExtinctionPyramid's constructor does:
// the same lattices (margin of ceil(3 sigma0 / spacing) nodes, every second node per level), the
// same normalised Gaussian taps, zeros beyond the input, the grid's boundary nodes at half weight,
// the same opacity conversion. Three scratch
// buffers rotate through the three separable passes of a level; every level's extinction lands in
// one buffer laid out as GpuExtinctionPyramid's.
// PyramidQuantity::step_opacity filters every level from the grid (kept in its own buffer) at
// stride 2^l, with that level's slab thickness as the conversion length, as the CPU does.
#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "shader_constants.h"
#include "occlusion/pyramid_filter_taps.h"
#include "occlusion_gl_util.h"
#include "penumbra/core/error.h"
#include "occlusion/gpu_occlusion.h"

namespace penumbra::render {
namespace gpu {
extern const char* const kPyramidFilterShader;  // render/shaders/pyramid_filter.comp
}  // namespace gpu

namespace {

using gpu::CurrentContext;
using gpu::DeviceBuffer;
using gpu::GlApi;

constexpr int kLocalSize = shader::kPyramidFilterGroup;  // pyramid_filter.comp's local_size_x
constexpr const char* kWho = "gpu_build_pyramid_levels";

// The CPU build's taps (pyramid_filter_taps.h) in float for the shader.
std::vector<float> gaussian_taps(double sigma_nodes, int& radius) {
  const std::vector<double> w = detail::gaussian_taps(sigma_nodes, radius);
  return std::vector<float>(w.begin(), w.end());
}

std::size_t volume(const std::array<int, 3>& d) { return static_cast<std::size_t>(d[0]) * d[1] * d[2]; }

// One separable pass: output count along `axis`, input node stride * o + offset, Gaussian sigma.
struct Pass {
  int axis, count, stride, offset;
  double sigma_nodes;
  bool halve_ends;  ///< the input is the grid: its first and last node along the axis count half
};

}  // namespace

GpuPyramidLevels gpu_build_pyramid_levels(const std::shared_ptr<GpuDevice>& device, const ExtinctionGrid& grid,
                                          const PyramidOptions& options) {
  require(device != nullptr, std::string(kWho) + ": device is null; expected GpuDevice::open()");
  grid.validate(kWho);
  require(std::isfinite(options.sigma0) && options.sigma0 >= 0,
          std::string(kWho) + ": sigma0 = " + std::to_string(options.sigma0) + "; expected finite >= 0 (0 = mean spacing)");
  require(options.max_levels >= 1, std::string(kWho) + ": max_levels = " + std::to_string(options.max_levels) + "; expected >= 1");
  const auto t0 = gpu::Clock::now();
  const double sigma0 = options.sigma0 > 0 ? options.sigma0 : grid.mean_spacing();
  const bool opacity = options.quantity == PyramidQuantity::opacity;
  // step_opacity: every level from the grid, as opacity of a slab kConeStepSigmas sigma_l thick.
  const bool step = options.quantity == PyramidQuantity::step_opacity;
  const double cell = grid.mean_spacing();
  auto thickness = [&](int l) { return kConeStepSigmas * sigma0 * std::ldexp(1.0, l); };
  int pad[3];
  double sigma_nodes0[3];
  for (int a = 0; a < 3; ++a) {
    sigma_nodes0[a] = sigma0 / grid.spacing[a];
    pad[a] = static_cast<int>(std::ceil(3.0 * sigma_nodes0[a]));
  }

  // The plan (pure bookkeeping, as the CPU constructor's loop): per level its three passes and
  // lattice.
  GpuPyramidLevels out;
  std::vector<std::array<Pass, 3>> passes;
  {
    int interior[3] = {grid.dims[0] - 1, grid.dims[1] - 1, grid.dims[2] - 1};
    for (int l = 0; l < options.max_levels; ++l) {
      if (l > 0 && std::max(interior[0], std::max(interior[1], interior[2])) <= 2) break;
      std::array<Pass, 3> p{};
      PyramidLevel level;
      level.spacing = grid.spacing * std::ldexp(1.0, l);
      level.sigma = sigma0 * std::ldexp(1.0, l);
      for (int a = 0; a < 3; ++a) {
        if (l > 0) interior[a] = (interior[a] + 1) / 2;
        if (step) {
          const int stride = 1 << l;
          p[static_cast<std::size_t>(a)] = {a, interior[a] + 1 + 2 * pad[a], stride, -pad[a] * stride, stride * sigma_nodes0[a], true};
        } else if (l == 0) {
          p[static_cast<std::size_t>(a)] = {a, grid.dims[static_cast<std::size_t>(a)] + 2 * pad[a], 1, -pad[a], sigma_nodes0[a], true};
        } else {
          p[static_cast<std::size_t>(a)] = {a, interior[a] + 1 + 2 * pad[a], 2, -pad[a], std::sqrt(3.0) * sigma_nodes0[a], false};
        }
        level.dims[static_cast<std::size_t>(a)] = p[static_cast<std::size_t>(a)].count;
        level.lo[a] = grid.lo[a] - pad[a] * level.spacing[a];
      }
      passes.push_back(p);
      out.levels.push_back(std::move(level));
    }
  }
  // Largest array any pass reads or writes.
  std::size_t scratch = volume(grid.dims), total = 0;
  {
    std::array<int, 3> dims = grid.dims;
    for (std::size_t l = 0; l < passes.size(); ++l) {
      if (step) dims = grid.dims;
      for (const Pass& p : passes[l]) {
        dims[static_cast<std::size_t>(p.axis)] = p.count;
        scratch = std::max(scratch, volume(dims));
      }
      total += volume(out.levels[l].dims);
    }
  }
  require(scratch < (std::size_t{1} << 31) && total < (std::size_t{1} << 31),
          std::string(kWho) + ": the grid is too large for the shader's 32-bit indices");

  GpuDevice::Impl& dev = device->impl();
  CurrentContext current(dev);
  const GlApi& gl = current.gl();
  const GLuint program = gpu::compile_compute_program(gl, gpu::kPyramidFilterShader, "pyramid-filter");
  DeviceBuffer buffers[3], taps, levels, source;
  auto release = [&] {
    for (DeviceBuffer& b : buffers) b.release(gl);
    source.release(gl);
    taps.release(gl);
    levels.release(gl);
    gl.DeleteProgram(program);
  };
  try {
    for (DeviceBuffer& b : buffers) b.reserve(gl, dev, scratch * sizeof(float), kWho, "filter scratch");
    levels.reserve(gl, dev, total * sizeof(float), kWho, "pyramid levels");
    if (step) source.reserve(gl, dev, volume(grid.dims) * sizeof(float), kWho, "extinction grid");
    taps.reserve(gl, dev, 64 * sizeof(float), kWho, "Gaussian taps");
    auto u1i = [&](const char* name, int v) { gl.ProgramUniform1i(program, gl.GetUniformLocation(program, name), v); };
    gl.ProgramUniform1f(program, gl.GetUniformLocation(program, "u_cell"), static_cast<float>(cell));
    gl.ProgramUniform1f(program, gl.GetUniformLocation(program, "u_max_opacity"), static_cast<float>(detail::kMaxOpacity));
    auto run = [&](int mode, GLuint src, GLuint dst, std::size_t count, std::size_t dst_offset) {
      u1i("u_mode", mode);
      u1i("u_dst_offset", static_cast<int>(dst_offset));
      gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, src);
      gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, dst);
      gl.BindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, taps.name);
      gpu::dispatch_chunked(gl, dev, program, count, kLocalSize);
    };

    // Level 0's input in buffers[0]: the grid, as opacity per cell when that is what is filtered.
    const std::size_t n_grid = volume(grid.dims);
    const auto t_upload = gpu::Clock::now();
    gl.NamedBufferSubData(step ? source.name : buffers[opacity ? 2 : 0].name, 0, static_cast<GLsizeiptr>(n_grid * sizeof(float)),
                          grid.tau.data());
    if (opacity) run(1, buffers[2].name, buffers[0].name, n_grid, 0);
    gl.Finish();
    const double upload_ms = ms_since(t_upload);

    const auto t_filter = gpu::Clock::now();
    std::array<int, 3> dims = grid.dims;
    std::size_t offset = 0;
    for (std::size_t l = 0; l < passes.size(); ++l) {
      if (step) {
        // This level's slab opacity from the grid.
        gl.ProgramUniform1f(program, gl.GetUniformLocation(program, "u_cell"), static_cast<float>(thickness(static_cast<int>(l))));
        run(1, source.name, buffers[0].name, n_grid, 0);
        dims = grid.dims;
      }
      // buffers[0] -> [1] -> [2] -> [0]: the level's filtered values end where its input was.
      for (std::size_t k = 0; k < 3; ++k) {
        const Pass& p = passes[l][k];
        int radius = 0;
        const std::vector<float> w = gaussian_taps(p.sigma_nodes, radius);
        taps.reserve(gl, dev, w.size() * sizeof(float), kWho, "Gaussian taps");
        gl.NamedBufferSubData(taps.name, 0, static_cast<GLsizeiptr>(w.size() * sizeof(float)), w.data());
        u1i("u_in_nx", dims[0]);
        u1i("u_in_ny", dims[1]);
        u1i("u_in_nz", dims[2]);
        dims[static_cast<std::size_t>(p.axis)] = p.count;
        u1i("u_out_nx", dims[0]);
        u1i("u_out_ny", dims[1]);
        u1i("u_axis", p.axis);
        u1i("u_stride", p.stride);
        u1i("u_offset", p.offset);
        u1i("u_radius", radius);
        u1i("u_halve_ends", p.halve_ends ? 1 : 0);
        run(0, buffers[k].name, buffers[(k + 1) % 3].name, volume(dims), 0);
      }
      // The level's extinction (converted back from opacity) into the levels buffer.
      run(opacity || step ? 2 : 3, buffers[0].name, levels.name, volume(dims), offset);
      offset += volume(dims);
    }
    gl.Finish();
    out.filter_ms = ms_since(t_filter);
    out.upload_ms = upload_ms;

    offset = 0;
    for (PyramidLevel& level : out.levels) {
      level.tau.resize(volume(level.dims));
      gl.GetNamedBufferSubData(levels.name, static_cast<GLintptr>(offset * sizeof(float)),
                               static_cast<GLsizeiptr>(level.tau.size() * sizeof(float)), level.tau.data());
      offset += level.tau.size();
    }
    const GLenum err = gl.GetError();
    if (err != GL_NO_ERROR)
      throw Error(err == GL_OUT_OF_MEMORY ? ErrorCode::out_of_memory : ErrorCode::internal_error,
                  std::string(kWho) + ": OpenGL reported " + gpu::gl_error_text(err));
  } catch (...) {
    release();
    throw;
  }
  release();
  out.build_ms = ms_since(t0);
  return out;
}

}  // namespace penumbra::render

// SPDX-License-Identifier: BSD-3-Clause
// render/src/occlusion/gl/occlusion_gl_util.h -- what the GPU cone tracer and the GPU pyramid
// build share: storage buffers that grow on demand, chunked dispatch (programs: gpu/gl_program.h)
#pragma once
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>

#include "gpu/gl_program.h"
#include "gpu/gpu_device_impl.h"
#include "penumbra/core/elapsed.h"
#include "penumbra/core/error.h"

namespace penumbra::render::gpu {

using Clock = std::chrono::steady_clock;

/// A storage buffer that grows on demand; checked against the device's limits. `who` names the
/// caller in errors.
struct DeviceBuffer {
  GLuint name = 0;
  std::size_t capacity = 0;

  void reserve(const GlApi& gl, const GpuDevice::Impl& dev, std::size_t bytes, const char* who, const char* what) {
    bytes = std::max<std::size_t>(bytes, 16);  // an empty storage buffer cannot be bound
    if (name != 0 && capacity >= bytes) return;
    const auto limit = static_cast<std::size_t>(dev.info.max_storage_block_bytes);
    if (limit > 0 && bytes > limit)
      throw Error(ErrorCode::out_of_memory, std::string(who) + ": the " + what + " need " + mib(bytes) +
                                                ", beyond the device's GL_MAX_SHADER_STORAGE_BLOCK_SIZE of " + mib(limit));
    if (dev.options.memory_limit_bytes > 0 && bytes > dev.options.memory_limit_bytes)
      throw Error(ErrorCode::out_of_memory, std::string(who) + ": the " + what + " need " + mib(bytes) +
                                                " but the configured limit is " + mib(dev.options.memory_limit_bytes));
    if (name == 0) gl.CreateBuffers(1, &name);
    while (gl.GetError() != GL_NO_ERROR) {
    }
    gl.NamedBufferData(name, static_cast<GLsizeiptr>(bytes), nullptr, GL_DYNAMIC_DRAW);
    const GLenum err = gl.GetError();
    if (err != GL_NO_ERROR) {
      capacity = 0;
      throw Error(err == GL_OUT_OF_MEMORY ? ErrorCode::out_of_memory : ErrorCode::internal_error,
                  std::string(who) + ": allocating " + mib(bytes) + " for the " + what + " failed with " +
                      gl_error_text(err));
    }
    capacity = bytes;
  }
  void release(const GlApi& gl) {
    if (name != 0) gl.DeleteBuffers(1, &name);
    name = 0;
    capacity = 0;
  }
};

/// Runs `count` invocations of `program` (local size `local_size`, uniforms u_first and u_count)
/// in dispatches within the device's work-group limit.
inline void dispatch_chunked(const GlApi& gl, const GpuDevice::Impl& dev, GLuint program, std::size_t count,
                             int local_size) {
  const std::size_t max_groups = static_cast<std::size_t>(std::clamp<std::int64_t>(dev.max_work_group_count_x, 1, 65535));
  const std::size_t chunk = max_groups * static_cast<std::size_t>(local_size);
  const GLint first_at = gl.GetUniformLocation(program, "u_first"), count_at = gl.GetUniformLocation(program, "u_count");
  gl.UseProgram(program);
  for (std::size_t first = 0; first < count; first += chunk) {
    const std::size_t n = std::min(chunk, count - first);
    gl.ProgramUniform1i(program, first_at, static_cast<GLint>(first));
    gl.ProgramUniform1i(program, count_at, static_cast<GLint>(n));
    gl.DispatchCompute(static_cast<GLuint>((n + local_size - 1) / local_size), 1, 1);
    gl.MemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
  }
  gl.UseProgram(0);
}

}  // namespace penumbra::render::gpu

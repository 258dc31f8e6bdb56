// SPDX-License-Identifier: BSD-3-Clause
// render/include/penumbra/render/gpu_ray_caster.h -- the ray caster on a GPU through headless EGL
#pragma once
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "penumbra/render/camera.h"
#include "penumbra/render/cpu_ray_caster.h"
#include "penumbra/render/egl_device.h"
#include "penumbra/render/image.h"
#include "penumbra/render/tet_mesh.h"
#include "penumbra/render/transfer_function.h"

#include "penumbra/core/export.h"

PNB_PUBLIC_BEGIN

namespace penumbra::render {

/// What the opened device is.
struct GpuDeviceInfo {
  std::string device;      ///< e.g. "EGL device 0 (/dev/dri/renderD128, hardware)" or "Mesa surfaceless platform"
  bool software = false;   ///< a CPU rasteriser (llvmpipe, softpipe, SwiftShader)
  std::string gl_version;  ///< GL_VERSION
  std::string gl_renderer; ///< GL_RENDERER
  std::string gl_vendor;   ///< GL_VENDOR
  std::int64_t max_storage_block_bytes = 0;  ///< GL_MAX_SHADER_STORAGE_BLOCK_SIZE
  std::int64_t free_memory_bytes = -1;       ///< from GL_NVX_gpu_memory_info, -1 if unknown
  /// One line for logs: device, renderer and GL version.
  std::string summary() const;
};

/// An OpenGL 4.5 core context without any window system, on the EGL device chosen by
/// select_egl_device. Several ray casters may share one device; its calls are serialised.
class GpuDevice {
public:
  /// Loads EGL, picks a device and creates the context; logs the device, GL version and
  /// renderer once. Throws Error(backend_unavailable) naming the reason (no libEGL, no
  /// device, no OpenGL 4.5 context) and never crashes when EGL is absent.
  static std::shared_ptr<GpuDevice> open(const GpuOptions& options = {});
  ~GpuDevice();
  GpuDevice(const GpuDevice&) = delete;
  GpuDevice& operator=(const GpuDevice&) = delete;

  const GpuDeviceInfo& info() const;
  const GpuOptions& options() const;

  struct Impl;
  Impl& impl() const { return *m_impl; }

private:
  explicit GpuDevice(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> m_impl;
};

/// Bytes held on the device for one mesh.
struct GpuMemoryStats {
  std::size_t tets = 0, points = 0, boundary_triangles = 0, bvh_nodes = 0;
  std::size_t geometry_bytes = 0;      ///< float32 xyz per point, 4 int32 vertex ids per tet
  std::size_t adjacency_bytes = 0;     ///< 4 int32 (neighbour << 2 | its face) per tet
  std::size_t scalar_bytes = 0;        ///< one float32 field value per point
  std::size_t acceleration_bytes = 0;  ///< boundary triangles and their BVH
  std::size_t frame_bytes = 0;         ///< transfer-function table and output tile (depend on the image, not the mesh)
  /// Geometry, adjacency and one scalar, per tet (the figure of Bernardon et al.'s 192 B/tet).
  double mesh_bytes_per_tet() const;
  /// Everything that scales with the mesh (all but frame_bytes), per tet.
  double total_bytes_per_tet() const;
};

/// The CPU ray caster's algorithm in OpenGL compute shaders: the same boundary entries (BVH
/// over the boundary faces), the same tet walk and tie rule, the same closed-form segment
/// integral and early termination, in float32 instead of float64. The mesh is uploaded once;
/// render() uploads only the blocks of field values that changed since the previous call.
/// render() may be called from any thread; calls on one device are serialised.
class GpuRayCaster final : public Renderer {
public:
  /// Uploads `mesh`. Throws Error(out_of_memory) naming the sizes when the mesh does not fit the
  /// device's storage-buffer limits, its free memory, or options().memory_limit_bytes.
  GpuRayCaster(std::shared_ptr<GpuDevice> device, std::shared_ptr<const TetMesh> mesh);
  ~GpuRayCaster();
  GpuRayCaster(const GpuRayCaster&) = delete;
  GpuRayCaster& operator=(const GpuRayCaster&) = delete;

  /// As CpuRayCaster::render.
  Image render(const std::vector<float>& scalars, const TransferFunction& tf, const Camera& camera,
               const RenderOptions& options = {});
  /// With RenderOptions::ray_runs, up to 16 runs per pixel: a pixel with more throws
  /// Error(invalid_argument) naming it (the CPU renderer returns them all).
  void render(const std::vector<float>& scalars, const TransferFunction& tf, const Camera& camera,
              const RenderOptions& options, RenderOutput& out) override;

  GpuMemoryStats memory() const;
  /// Field bytes sent to the device by the last render() (0 when the values were unchanged).
  std::size_t last_scalar_upload_bytes() const;
  const TetMesh& mesh() const override;
  const char* backend() const override { return "gpu"; }
  /// Keeps the tets, their adjacency and Morton order on the device and sends the moved points
  /// and the boundary's new BVH (the points' and the BVH's bytes).
  void move_points(std::shared_ptr<const TetMesh> moved) override;
  const GpuDevice& device() const;

private:
  struct Impl;
  std::unique_ptr<Impl> m_impl;
};

}  // namespace penumbra::render

PNB_PUBLIC_END

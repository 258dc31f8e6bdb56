// SPDX-License-Identifier: BSD-3-Clause
// render/src/gpu/gpu_unavailable.cpp -- the GPU API in builds without EGL (PNB_ENABLE_EGL=OFF):
// every entry point reports Error(backend_unavailable), so callers need no #ifdefs.
#include "penumbra/core/error.h"
#include "penumbra/render/gpu_ray_caster.h"

namespace penumbra::render {
namespace {

[[noreturn]] void unavailable() {
  throw Error(ErrorCode::backend_unavailable,
              "GPU backend: this build has no GPU backend (configured with PNB_ENABLE_EGL=OFF or without EGL and "
              "OpenGL headers); use the cpu backend or rebuild with libegl-dev and libgl-dev installed");
}

}  // namespace

struct GpuDevice::Impl {};
struct GpuRayCaster::Impl {};

std::shared_ptr<GpuDevice> GpuDevice::open(const GpuOptions&) { unavailable(); }
GpuDevice::GpuDevice(std::unique_ptr<Impl> impl) : m_impl(std::move(impl)) {}
GpuDevice::~GpuDevice() = default;
const GpuDeviceInfo& GpuDevice::info() const { unavailable(); }
const GpuOptions& GpuDevice::options() const { unavailable(); }

GpuRayCaster::GpuRayCaster(std::shared_ptr<GpuDevice>, std::shared_ptr<const TetMesh>) { unavailable(); }
GpuRayCaster::~GpuRayCaster() = default;
Image GpuRayCaster::render(const std::vector<float>&, const TransferFunction&, const Camera&, const RenderOptions&) {
  unavailable();
}
void GpuRayCaster::move_points(std::shared_ptr<const TetMesh>) { unavailable(); }
GpuMemoryStats GpuRayCaster::memory() const { unavailable(); }
std::size_t GpuRayCaster::last_scalar_upload_bytes() const { unavailable(); }
void GpuRayCaster::render(const std::vector<float>&, const TransferFunction&, const Camera&, const RenderOptions&,
                          RenderOutput&) {
  unavailable();
}
const TetMesh& GpuRayCaster::mesh() const { unavailable(); }
const GpuDevice& GpuRayCaster::device() const { unavailable(); }

std::vector<EglDeviceInfo> list_egl_devices(const GpuOptions&) { unavailable(); }
bool hardware_gpu_present(const GpuOptions&) noexcept { return false; }
bool gpu_backend_compiled() noexcept { return false; }

}  // namespace penumbra::render

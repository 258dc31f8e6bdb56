// SPDX-License-Identifier: BSD-3-Clause
// render/src/occlusion/gpu_occlusion_unavailable.cpp -- the GPU cone tracer in builds without EGL
// (PNB_ENABLE_EGL=OFF): every entry point reports Error(backend_unavailable), so callers need no
// #ifdefs.
#include "penumbra/core/error.h"
#include "occlusion/gpu_occlusion.h"

namespace penumbra::render {
namespace {

[[noreturn]] void unavailable() {
  throw Error(ErrorCode::backend_unavailable,
              "GPU backend: this build has no GPU cone tracer (configured with PNB_ENABLE_EGL=OFF or without EGL and "
              "OpenGL headers); use ConeTracer on the CPU or rebuild with libegl-dev and libgl-dev installed");
}

}  // namespace

struct GpuExtinctionPyramid::Impl {};
struct GpuConeTracer::Impl {};

GpuExtinctionPyramid::GpuExtinctionPyramid(std::shared_ptr<GpuDevice>, const ExtinctionPyramid&) { unavailable(); }
GpuExtinctionPyramid::~GpuExtinctionPyramid() = default;
void GpuExtinctionPyramid::update(const ExtinctionPyramid&) { unavailable(); }
const ExtinctionPyramid& GpuExtinctionPyramid::host() const { unavailable(); }
std::size_t GpuExtinctionPyramid::level_bytes() const { unavailable(); }
double GpuExtinctionPyramid::upload_ms() const { unavailable(); }

GpuPyramidLevels gpu_build_pyramid_levels(const std::shared_ptr<GpuDevice>&, const ExtinctionGrid&, const PyramidOptions&) {
  unavailable();
}

GpuConeTracer::GpuConeTracer(const GpuExtinctionPyramid&, const ConeOptions&) { unavailable(); }
GpuConeTracer::~GpuConeTracer() = default;
const ConeTracer& GpuConeTracer::host() const { unavailable(); }
std::vector<float> GpuConeTracer::transmittance(const ConeTarget&, const std::vector<Vec3d>&) const { unavailable(); }
GpuPreIllumination GpuConeTracer::pre_illumination(const ConeTarget&, const Bounds&, int) const { unavailable(); }
std::vector<float> GpuConeTracer::at_mesh_points(const ConeTarget&, const std::shared_ptr<const TetMesh>&, int) const {
  unavailable();
}

}  // namespace penumbra::render

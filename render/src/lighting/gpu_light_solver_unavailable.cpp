// SPDX-License-Identifier: BSD-3-Clause
// render/src/lighting/gpu_light_solver_unavailable.cpp -- the GPU light volume in builds without
// EGL (PNB_ENABLE_EGL=OFF): constructing it reports Error(backend_unavailable).
#include "gpu_light_solver.h"

#include "penumbra/core/error.h"

namespace penumbra::render::lighting {
namespace {

[[noreturn]] void unavailable() {
  throw Error(ErrorCode::backend_unavailable,
              "LightVolume: options.device asks for the GPU light solve, but this build has no GPU backend "
              "(configured with PNB_ENABLE_EGL=OFF or without EGL and OpenGL headers); leave options.device null "
              "for the CPU solve or rebuild with libegl-dev and libgl-dev installed");
}

}  // namespace

struct GpuLightBuffers {};
struct GpuLightSolver::Impl {};

GpuLightSolver::GpuLightSolver(std::shared_ptr<GpuDevice>, const TetMesh&, const Level1Topology&, const std::vector<float>&,
                               const std::vector<Bounds>&) {
  unavailable();
}
GpuLightSolver::~GpuLightSolver() = default;
void GpuLightSolver::move_points(const TetMesh&, const Level1Topology&, const std::vector<float>&) { unavailable(); }
void GpuLightSolver::set_grid(const Level0Grid&) { unavailable(); }
void GpuLightSolver::set_field(const Level0Grid&, const Level1Field&) { unavailable(); }
std::shared_ptr<GpuLightBuffers> GpuLightSolver::new_light() { unavailable(); }
void GpuLightSolver::solve_level0(GpuLightBuffers&, const Light&, double, std::vector<float>&) { unavailable(); }
void GpuLightSolver::set_order(GpuLightBuffers&, const VertexOrder&) { unavailable(); }
void GpuLightSolver::set_rho1(GpuLightBuffers&, const std::vector<float>&) { unavailable(); }
double GpuLightSolver::level1_pass(GpuLightBuffers&, const Light&, const Level1Context&, std::vector<float>&,
                                   std::size_t&) {
  unavailable();
}
void GpuLightSolver::set_scatter_source(const std::vector<float>&, const std::vector<float>&) { unavailable(); }
int GpuLightSolver::scatter(int, double, const std::array<double, 3>&, double&) { unavailable(); }
void GpuLightSolver::read_scatter(std::vector<float>&) { unavailable(); }

}  // namespace penumbra::render::lighting

// SPDX-License-Identifier: BSD-3-Clause
// bench/gpu/vtk_projected_tetra_bench.cpp -- renders a benchmark scene with VTK 9's
// vtkProjectedTetrahedraMapper (cell projection through OpenGL rasterisation, the classic GPU
// peer of a ray caster) and measures its error against Penumbra's cached reference image.
//
// Usage: pnb_bench_gpu_vtk --scene NAME --data-dir DIR [--frames N] [--size WxH]
// Debian's VTK renders through X11 only: run it under xvfb-run. Prints one JSON object.
#include <vtkColorTransferFunction.h>
#include <vtkNew.h>
#include <vtkOpenGLRenderWindow.h>
#include <vtkPiecewiseFunction.h>
#include <vtkProjectedTetrahedraMapper.h>
#include <vtkRenderWindow.h>
#include <vtkSmartPointer.h>
#include <vtkUnstructuredGrid.h>
#include <vtkVolumeProperty.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <iostream>
#include <sstream>

#include "bench_util.h"
#include "penumbra/core/error.h"
#include "penumbra/render/image.h"
#include "scene.h"
#include "frame_report.h"
#include "vtk_scene.h"
#include "vtk_window.h"

namespace pb = penumbra::bench;
namespace pr = penumbra::render;

namespace {

// The projected-tetrahedra mapper keeps the opacity function's value per vertex in 8 bits (so in
// [0, 1]) and composites 1 - exp(-a * thickness / unit distance). An extinction tau per world
// unit is therefore a = tau / tau_max over a unit distance of 1 / tau_max.
vtkSmartPointer<vtkVolumeProperty> make_property(const pb::Scene& scene) {
  double tau_max = 0;
  for (const pb::TfNode& n : scene.tf) tau_max = std::max(tau_max, n.extinction);
  if (!(tau_max > 0)) tau_max = 1;
  vtkNew<vtkColorTransferFunction> color;
  color->SetColorSpaceToRGB();
  vtkNew<vtkPiecewiseFunction> opacity;
  for (const pb::TfNode& n : scene.tf) {
    color->AddRGBPoint(n.x, n.r, n.g, n.b);
    opacity->AddPoint(n.x, n.extinction / tau_max);
  }
  auto property = vtkSmartPointer<vtkVolumeProperty>::New();
  property->SetColor(color);
  property->SetScalarOpacity(opacity);
  property->SetScalarOpacityUnitDistance(1.0 / tau_max);
  property->SetInterpolationTypeToLinear();
  property->ShadeOff();
  return property;
}

// "llvmpipe (LLVM 15.0.6, 256 bits)" from the window's capability report.
std::string renderer_string(vtkRenderWindow* window) {
  auto* gl = vtkOpenGLRenderWindow::SafeDownCast(window);
  if (gl == nullptr) return "unknown";
  std::istringstream report(gl->ReportCapabilities());
  for (std::string line; std::getline(report, line);) {
    const std::string key = "OpenGL renderer string:";
    const auto at = line.find(key);
    if (at == std::string::npos) continue;
    std::string v = line.substr(at + key.size());
    v.erase(0, v.find_first_not_of(" \t"));
    return v;
  }
  return "unknown";
}

int run(int argc, char** argv) {
  const std::string name = pb::option(argc, argv, "scene", "");
  const std::string data_dir = pb::option(argc, argv, "data-dir", "");
  const int frames = std::stoi(pb::option(argc, argv, "frames", "5"));
  const std::string size = pb::option(argc, argv, "size", "");
  penumbra::require(!name.empty() && !data_dir.empty(), "pnb_bench_gpu_vtk: --scene NAME and --data-dir DIR are required");
  penumbra::require(frames >= 1, "pnb_bench_gpu_vtk: --frames must be >= 1");
  pb::Scene scene = pb::load_scene(name, data_dir);
  if (!size.empty()) {
    int w = 0, h = 0;
    penumbra::require(std::sscanf(size.c_str(), "%dx%d", &w, &h) == 2 && w > 0 && h > 0,
                      "pnb_bench_gpu_vtk: --size '" + size + "', expected WxH");
    scene.width = w;
    scene.height = h;
  }
  const std::string tag = scene.name + (size.empty() ? "" : "-" + size);
  const std::string ref_path = pb::reference_path(scene, data_dir);
  const std::vector<unsigned char> reference =
      pb::cached_reference(scene, data_dir, "pnb_bench_gpu_vtk", "pnb_bench_gpu_penumbra");

  const vtkSmartPointer<vtkUnstructuredGrid> grid = pb::make_grid(scene);
  vtkNew<vtkProjectedTetrahedraMapper> mapper;
  mapper->SetInputData(grid);
  const vtkSmartPointer<vtkRenderWindow> window = pb::scene_window(scene, mapper, make_property(scene));

  pb::Stopwatch first_clock;
  window->Render();
  const double first_ms = first_clock.ms();
  std::fprintf(stderr, "pnb_bench_gpu_vtk: %s warm-up frame: %.1f ms\n", tag.c_str(), first_ms);
  std::vector<double> times;
  for (int f = 0; f < frames; ++f) {
    pb::Stopwatch clock;
    window->Render();
    times.push_back(clock.ms());
  }
  const std::vector<unsigned char> rgb = pb::read_back(window, scene.width, scene.height, "pnb_bench_gpu_vtk");
  nlohmann::ordered_json line = pb::frame_line("gpu", "vtk-projected-tetra", scene, times, rgb, reference,
                                               data_dir + "/images/" + tag + "-vtk-projected-tetra.png");
  line["device"] = renderer_string(window);
  line["first_frame_ms"] = pb::rounded(first_ms, 1);
  line["load_avg"] = pb::load_average();
  line["reference"] = ref_path;
  std::cout << line.dump() << std::endl;
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return penumbra::bench::guarded_main("pnb_bench_gpu_vtk", run, argc, argv); }

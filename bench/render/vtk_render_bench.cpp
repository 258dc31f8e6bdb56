// SPDX-License-Identifier: BSD-3-Clause
// bench/render/vtk_render_bench.cpp -- renders a benchmark scene with VTK 9's unstructured-grid
// volume mappers (vtkUnstructuredGridVolumeRayCastMapper, vtkUnstructuredGridVolumeZSweepMapper)
// and measures their error against Penumbra's cached double-precision reference image.
//
// Usage: pnb_bench_render_vtk --scene NAME --data-dir DIR [--frames N]
//                             [--renderers vtk-raycast,vtk-zsweep] [--integrator linear|default]
// Debian's VTK renders through X11 only: run it under xvfb-run. Prints one JSON object per mapper.
#include <vtkColorTransferFunction.h>
#include <vtkNew.h>
#include <vtkPiecewiseFunction.h>
#include <vtkRenderWindow.h>
#include <vtkSmartPointer.h>
#include <vtkUnstructuredGrid.h>
#include <vtkUnstructuredGridLinearRayIntegrator.h>
#include <vtkUnstructuredGridVolumeMapper.h>
#include <vtkUnstructuredGridVolumeRayCastMapper.h>
#include <vtkUnstructuredGridVolumeZSweepMapper.h>
#include <vtkVolumeProperty.h>

#include <nlohmann/json.hpp>

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

// One node list for colour and opacity: VTK's unstructured integrators take breakpoints from
// the colour function only. With a unit distance of 1, the opacity value is the extinction per
// world unit (the linear integrator divides the opacity by ScalarOpacityUnitDistance).
vtkSmartPointer<vtkVolumeProperty> make_property(const pb::Scene& scene) {
  vtkNew<vtkColorTransferFunction> color;
  color->SetColorSpaceToRGB();
  vtkNew<vtkPiecewiseFunction> opacity;
  for (const pb::TfNode& n : scene.tf) {
    color->AddRGBPoint(n.x, n.r, n.g, n.b);
    opacity->AddPoint(n.x, n.extinction);
  }
  auto property = vtkSmartPointer<vtkVolumeProperty>::New();
  property->SetColor(color);
  property->SetScalarOpacity(opacity);
  property->SetScalarOpacityUnitDistance(1.0);
  property->SetInterpolationTypeToLinear();
  property->ShadeOff();
  return property;
}

template <class Mapper>
void fix_resolution(Mapper* mapper) {
  // By default both mappers lower their image resolution to meet a frame-rate budget.
  mapper->SetAutoAdjustSampleDistances(0);
  mapper->SetImageSampleDistance(1.0f);
  mapper->SetMinimumImageSampleDistance(1.0f);
  mapper->SetMaximumImageSampleDistance(1.0f);
}

vtkSmartPointer<vtkUnstructuredGridVolumeMapper> make_mapper(const std::string& renderer, bool linear_integrator) {
  vtkSmartPointer<vtkUnstructuredGridVolumeRayIntegrator> integrator;
  if (linear_integrator) integrator = vtkSmartPointer<vtkUnstructuredGridLinearRayIntegrator>::New();
  if (renderer == "vtk-raycast") {
    auto m = vtkSmartPointer<vtkUnstructuredGridVolumeRayCastMapper>::New();
    fix_resolution(m.Get());
    if (integrator) m->SetRayIntegrator(integrator);
    return m;
  }
  if (renderer == "vtk-zsweep") {
    auto m = vtkSmartPointer<vtkUnstructuredGridVolumeZSweepMapper>::New();
    fix_resolution(m.Get());
    if (integrator) m->SetRayIntegrator(integrator);
    return m;
  }
  throw penumbra::Error(penumbra::ErrorCode::invalid_argument,
                        "pnb_bench_render_vtk: unknown renderer '" + renderer + "', expected vtk-raycast or vtk-zsweep");
}

nlohmann::ordered_json bench_mapper(const pb::Scene& scene, vtkUnstructuredGrid* grid, const std::string& renderer,
                                    bool linear_integrator, int frames, const std::vector<unsigned char>& reference,
                                    const std::string& data_dir) {
  auto mapper = make_mapper(renderer, linear_integrator);
  mapper->SetInputData(grid);
  const vtkSmartPointer<vtkRenderWindow> window = pb::scene_window(scene, mapper, make_property(scene));

  // The first frame includes window creation and each mapper's per-mesh set-up.
  pb::Stopwatch first_clock;
  window->Render();
  const double first_ms = first_clock.ms();
  std::fprintf(stderr, "pnb_bench_render_vtk: %s %s warm-up frame: %.1f ms\n", scene.name.c_str(), renderer.c_str(),
               first_ms);
  std::vector<double> times;
  for (int f = 0; f < frames; ++f) {
    pb::Stopwatch frame_clock;
    window->Render();
    times.push_back(frame_clock.ms());
    std::fprintf(stderr, "pnb_bench_render_vtk: %s %s frame %d: %.1f ms\n", scene.name.c_str(), renderer.c_str(), f + 1,
                 times.back());
  }
  const std::vector<unsigned char> rgb = pb::read_back(window, scene.width, scene.height, "pnb_bench_render_vtk");
  nlohmann::ordered_json line = pb::frame_line("render", renderer, scene, times, rgb, reference,
                                               data_dir + "/images/" + scene.name + "-" + renderer + ".png");
  line["integrator"] = linear_integrator ? "vtkUnstructuredGridLinearRayIntegrator" : "default";
  line["first_frame_ms"] = pb::rounded(first_ms, 1);
  line["load_avg"] = pb::load_average();
  return line;
}

int run(int argc, char** argv) {
  const std::string name = pb::option(argc, argv, "scene", "");
  const std::string data_dir = pb::option(argc, argv, "data-dir", "");
  const int frames = std::stoi(pb::option(argc, argv, "frames", "5"));
  const std::string renderers = pb::option(argc, argv, "renderers", "vtk-raycast,vtk-zsweep");
  const std::string integrator = pb::option(argc, argv, "integrator", "linear");
  penumbra::require(!name.empty() && !data_dir.empty(), "pnb_bench_render_vtk: --scene NAME and --data-dir DIR are required");
  penumbra::require(frames >= 1, "pnb_bench_render_vtk: --frames must be >= 1");
  penumbra::require(integrator == "linear" || integrator == "default",
                    "pnb_bench_render_vtk: --integrator '" + integrator + "', expected linear or default");

  const pb::Scene scene = pb::load_scene(name, data_dir);
  // Without a reference (only with --no-reference 1, for checking set-ups) errors are left out.
  const bool no_reference = pb::option(argc, argv, "no-reference", "0") != "0";
  const std::vector<unsigned char> reference =
      no_reference ? std::vector<unsigned char>{}
                   : pb::cached_reference(scene, data_dir, "pnb_bench_render_vtk", "pnb_bench_render_penumbra");

  const vtkSmartPointer<vtkUnstructuredGrid> grid = pb::make_grid(scene);
  std::stringstream list(renderers);
  for (std::string renderer; std::getline(list, renderer, ',');)
    std::cout << bench_mapper(scene, grid, renderer, integrator == "linear", frames, reference, data_dir).dump()
              << std::endl;
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return penumbra::bench::guarded_main("pnb_bench_render_vtk", run, argc, argv); }

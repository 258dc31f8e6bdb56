// SPDX-License-Identifier: BSD-3-Clause
// bench/render/penumbra_render_bench.cpp -- times Penumbra's CPU ray caster on a benchmark scene
// and measures its error against the double-precision reference renderer.
//
// Usage: pnb_bench_render_penumbra --scene NAME --data-dir DIR [--frames N] [--refresh-reference 1]
// Prints one JSON object on stdout. Writes DIR/images/NAME-penumbra-cpu.png and caches the
// reference image as DIR/reference/NAME-WxH-DIGEST.png (computed only when missing).
#include <nlohmann/json.hpp>

#include <cstdio>
#include <exception>
#include <filesystem>
#include <iostream>
#include <memory>

#include "bench_util.h"
#include "penumbra/core/error.h"
#include "penumbra/core/thread_pool.h"
#include "penumbra/render/cpu_ray_caster.h"
#include "penumbra/render/image.h"
#include "scene.h"
#include "frame_report.h"
#include "scene_views.h"

namespace pb = penumbra::bench;
namespace pr = penumbra::render;

namespace {

int run(int argc, char** argv) {
  const std::string name = pb::option(argc, argv, "scene", "");
  const std::string data_dir = pb::option(argc, argv, "data-dir", "");
  const int frames = std::stoi(pb::option(argc, argv, "frames", "5"));
  const bool refresh = pb::option(argc, argv, "refresh-reference", "0") != "0";
  penumbra::require(!name.empty() && !data_dir.empty(),
                    "pnb_bench_render_penumbra: --scene NAME and --data-dir DIR are required");
  penumbra::require(frames >= 1, "pnb_bench_render_penumbra: --frames must be >= 1");

  pb::Stopwatch load_clock;
  const pb::Scene scene = pb::load_scene(name, data_dir);
  const double load_ms = load_clock.ms();

  // Mesh preparation and acceleration structures are built once per topology in a run, so
  // they are reported apart from the per-frame time.
  pb::Stopwatch prepare_clock;
  auto mesh = std::make_shared<const pr::TetMesh>(pr::prepare_tet_mesh(pb::mesh_view(scene), "bench"));
  const pr::CpuRayCaster caster(mesh);
  const double prepare_ms = prepare_clock.ms();

  const pr::TransferFunction tf = pb::transfer_function(scene);
  const pr::Camera cam = pb::camera(scene);

  // The reference takes minutes at 1M tets; it depends only on the scene, so it is cached.
  const std::string ref_path = pb::reference_path(scene, data_dir);
  double reference_ms = -1;
  const std::vector<unsigned char> reference = pb::reference_image(scene, *mesh, data_dir, refresh, reference_ms);

  pr::Image image = caster.render(scene.scalars, tf, cam);  // warm-up: first touch of caches and pages
  std::vector<double> times;
  for (int f = 0; f < frames; ++f) {
    pb::Stopwatch frame_clock;
    image = caster.render(scene.scalars, tf, cam);
    times.push_back(frame_clock.ms());
  }
  const std::vector<unsigned char> rgb = pr::to_rgb8(image, scene.background);
  nlohmann::ordered_json line = pb::frame_line("render", "penumbra-cpu", scene, times, rgb, reference,
                                               data_dir + "/images/" + scene.name + "-penumbra-cpu.png");
  line["threads"] = penumbra::worker_count();
  line["load_ms"] = pb::rounded(load_ms, 1);
  line["prepare_ms"] = pb::rounded(prepare_ms, 1);
  if (reference_ms >= 0) line["reference_ms"] = pb::rounded(reference_ms, 1);
  line["reference"] = ref_path;
  line["load_avg"] = pb::load_average();
  std::cout << line.dump() << std::endl;
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return penumbra::bench::guarded_main("pnb_bench_render_penumbra", run, argc, argv); }

// SPDX-License-Identifier: BSD-3-Clause
// bench/gpu/penumbra_gpu_bench.cpp -- times Penumbra's GPU ray caster (EGL + OpenGL compute)
// and its CPU ray caster on one benchmark scene, in the same run, with their errors against the
// double-precision reference and the GPU image's difference from the CPU image.
//
// Usage: pnb_bench_gpu_penumbra --scene NAME --data-dir DIR [--frames N] [--size WxH]
// Prints one JSON object per renderer (penumbra-gpu, penumbra-cpu) on stdout. Writes
// DIR/images/NAME[-WxH]-penumbra-{gpu,cpu}.png and caches the reference image as the render
// benchmark does (computed only when missing).
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
#include "penumbra/render/gpu_ray_caster.h"
#include "penumbra/render/image.h"
#include "scene.h"
#include "frame_report.h"
#include "scene_views.h"

namespace pb = penumbra::bench;
namespace pr = penumbra::render;

namespace {

// Median frame time of `frames` renders after one warm-up; `last` receives the last image.
template <class Render>
std::vector<double> time_frames(int frames, Render&& render, pr::Image& last) {
  last = render();
  std::vector<double> times;
  for (int f = 0; f < frames; ++f) {
    pb::Stopwatch clock;
    last = render();
    times.push_back(clock.ms());
  }
  return times;
}

int run(int argc, char** argv) {
  const std::string name = pb::option(argc, argv, "scene", "");
  const std::string data_dir = pb::option(argc, argv, "data-dir", "");
  const int frames = std::stoi(pb::option(argc, argv, "frames", "5"));
  const std::string size = pb::option(argc, argv, "size", "");
  penumbra::require(!name.empty() && !data_dir.empty(), "pnb_bench_gpu_penumbra: --scene NAME and --data-dir DIR are required");
  penumbra::require(frames >= 1, "pnb_bench_gpu_penumbra: --frames must be >= 1");

  pb::Stopwatch load_clock;
  pb::Scene scene = pb::load_scene(name, data_dir);
  const double load_ms = load_clock.ms();
  if (!size.empty()) {
    // A smaller image of the same scene, for software devices; the reference is keyed by size.
    int w = 0, h = 0;
    penumbra::require(std::sscanf(size.c_str(), "%dx%d", &w, &h) == 2 && w > 0 && h > 0,
                      "pnb_bench_gpu_penumbra: --size '" + size + "', expected WxH");
    scene.width = w;
    scene.height = h;
  }
  const std::string tag = scene.name + (size.empty() ? "" : "-" + size);

  pb::Stopwatch prepare_clock;
  auto mesh = std::make_shared<const pr::TetMesh>(pr::prepare_tet_mesh(pb::mesh_view(scene), "bench"));
  const double mesh_ms = prepare_clock.ms();
  pb::Stopwatch cpu_clock;
  const pr::CpuRayCaster cpu(mesh);
  const double cpu_prepare_ms = mesh_ms + cpu_clock.ms();
  pb::Stopwatch device_clock;
  std::string device_line;
  pr::GpuOptions options;
  options.log = [&](const std::string& s) { device_line = s; };
  const auto device = pr::GpuDevice::open(options);
  const double device_ms = device_clock.ms();
  std::fprintf(stderr, "pnb_bench_gpu_penumbra: %s\n", device_line.c_str());
  pb::Stopwatch upload_clock;
  pr::GpuRayCaster gpu(device, mesh);
  const double upload_ms = upload_clock.ms();

  const pr::TransferFunction tf = pb::transfer_function(scene);
  const pr::Camera cam = pb::camera(scene);

  const std::string ref_path = pb::reference_path(scene, data_dir);
  double reference_ms = -1;
  const std::vector<unsigned char> reference = pb::reference_image(scene, *mesh, data_dir, false, reference_ms);

  pr::Image gpu_image, cpu_image;
  std::fprintf(stderr, "pnb_bench_gpu_penumbra: %s penumbra-gpu, %d frames\n", tag.c_str(), frames);
  const auto gpu_times = time_frames(frames, [&] { return gpu.render(scene.scalars, tf, cam); }, gpu_image);
  std::fprintf(stderr, "pnb_bench_gpu_penumbra: %s penumbra-cpu, %d frames\n", tag.c_str(), frames);
  const auto cpu_times = time_frames(frames, [&] { return cpu.render(scene.scalars, tf, cam); }, cpu_image);
  // A new time step: every field value changes and is sent again (the mesh is not).
  std::vector<float> next = scene.scalars;
  for (float& s : next) s = std::nextafter(s, 2.0f);
  pb::Stopwatch step_clock;
  gpu.render(next, tf, cam);
  const double new_field_frame_ms = step_clock.ms();

  const auto gpu_rgb = pr::to_rgb8(gpu_image, scene.background);
  const auto cpu_rgb = pr::to_rgb8(cpu_image, scene.background);
  const pr::GpuMemoryStats mem = gpu.memory();
  const pr::GpuDeviceInfo& info = device->info();
  auto line = [&](const char* renderer, const std::vector<double>& times, const std::vector<unsigned char>& rgb) {
    return pb::frame_line("gpu", renderer, scene, times, rgb, reference,
                          data_dir + "/images/" + tag + "-" + renderer + ".png");
  };
  nlohmann::ordered_json g = line("penumbra-gpu", gpu_times, gpu_rgb);
  const pb::ImageError vs_cpu = pb::compare_rgb8(gpu_rgb, cpu_rgb);
  g["device"] = info.device + (info.software ? " [software]" : "") + ": " + info.gl_renderer;
  g["gl_version"] = info.gl_version;
  g["gpu_bytes_per_tet"] = pb::rounded(mem.total_bytes_per_tet(), 2);
  g["gpu_mesh_bytes_per_tet"] = pb::rounded(mem.mesh_bytes_per_tet(), 2);
  g["gpu_frame_bytes"] = mem.frame_bytes;
  g["rms_vs_cpu_pct"] = pb::rounded(pr::rms_difference_pct(gpu_rgb, cpu_rgb), 4);
  g["max_abs_vs_cpu"] = vs_cpu.max_abs;
  g["new_field_frame_ms"] = pb::rounded(new_field_frame_ms);
  g["load_ms"] = pb::rounded(load_ms, 1);
  g["prepare_ms"] = pb::rounded(mesh_ms + device_ms + upload_ms, 1);
  g["device_open_ms"] = pb::rounded(device_ms, 1);
  g["upload_ms"] = pb::rounded(upload_ms, 1);
  if (reference_ms >= 0) g["reference_ms"] = pb::rounded(reference_ms, 1);
  g["reference"] = ref_path;
  g["load_avg"] = pb::load_average();
  nlohmann::ordered_json c = line("penumbra-cpu", cpu_times, cpu_rgb);
  c["device"] = "cpu";
  c["threads"] = penumbra::worker_count();
  c["load_ms"] = pb::rounded(load_ms, 1);
  c["prepare_ms"] = pb::rounded(cpu_prepare_ms, 1);
  c["reference"] = ref_path;
  c["load_avg"] = pb::load_average();
  std::cout << g.dump() << "\n" << c.dump() << std::endl;
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return penumbra::bench::guarded_main("pnb_bench_gpu_penumbra", run, argc, argv); }

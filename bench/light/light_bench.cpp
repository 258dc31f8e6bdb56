// SPDX-License-Identifier: BSD-3-Clause
// bench/light/light_bench.cpp -- the two-level light volume in the style of Shih et al.'s Table 2
//
// Usage: pnb_bench_light --scene NAME --data-dir DIR [--levels "16 32 64 128 256"] [--samples N]
//        [--frames N] [--parts "sweep 1m gpu budget"] [--budget-pct P]
// Prints JSON lines on stdout:
//   bench "light"        one per (level-0 size, mode none / level0-only / two-level): timings of
//                        level-0 propagation, level-0 scattering (none: scattering runs once, on
//                        the mesh), level-1 propagation and scattering, and the error;
//   bench "light-1m"     a full update (resampling, both levels, scattering) with one light that
//                        moved (cold) and after a field change with the same light (warm);
//                        With a GPU backend a second "light-1m" line has backend "gpu": the same
//                        cold update solved by the compute shaders (GpuDevice::open, hardware
//                        or llvmpipe), and its agreement with the CPU solve of the same light
//                        (max and mean |rho_gpu - rho_cpu| over the vertices, level 1);
//   bench "light-budget" frames to converge with a per-frame budget of 8 % of a render frame
//                        (--budget-pct), one line per start: cold, time-step, light-moved.
// Errors, both against T, the double-precision transmittance to the light
// (LightTransmittanceReference), with mode "none" the error of no lighting (rho = 1):
//   rms_error_pct        image: the frame shaded by rho (the light's level-1 solution before
//                        scattering, as a grey light field, no Phong terms) against the frame
//                        shaded by T at every point, both by the CPU ray caster, so that the
//                        difference is the light's alone; RMS in % of 255 (--image-size, 256);
//   vertex_rms_error_pct RMS over N sampled vertices of |rho - T|, in % of the full light.
// T at every point takes a minute at 1M tets; it is cached in DIR/light-reference.
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <ctime>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <random>
#include <sstream>

#include "bench_util.h"
#include "penumbra/core/error.h"
#include "penumbra/core/thread_pool.h"
#include "penumbra/render/cpu_ray_caster.h"
#include "penumbra/render/gpu_ray_caster.h"
#include "penumbra/render/image.h"
#include "penumbra/render/light_volume.h"
#include "scene.h"
#include "scene_views.h"

namespace pb = penumbra::bench;
namespace pr = penumbra::render;

namespace {

// Process CPU time over all threads: on a shared machine it shows the work apart from waiting.
double cpu_ms() { return 1000.0 * static_cast<double>(std::clock()) / CLOCKS_PER_SEC; }

// The benchmark light turned by `step` degrees about z: a light that moved.
pr::Light moved(pr::Light light, int step) {
  const double a = step * 3.14159265358979 / 180.0, c = std::cos(a), s = std::sin(a);
  const penumbra::Vec3d v = light.vector;
  light.vector = {c * v.x - s * v.y, s * v.x + c * v.y, v.z};
  return light;
}

// Optical depth to `light` from every point, cached by scene and light: the reference is exact
// and slow (a search over all tets per point).
std::vector<double> reference_depths(const pb::Scene& scene, const std::shared_ptr<const pr::TetMesh>& mesh,
                                     const pr::TransferFunction& tf, const pr::Light& light, const std::string& dir) {
  char key[128];
  std::snprintf(key, sizeof key, "%s-%s-%.17g_%.17g_%.17g.f64", scene.name.c_str(), pb::scene_digest(scene).c_str(),
                light.vector.x, light.vector.y, light.vector.z);
  const std::string path = dir + "/light-reference/" + key;
  std::vector<double> depth(mesh->points.size());
  if (std::ifstream in{path, std::ios::binary}) {
    in.read(reinterpret_cast<char*>(depth.data()), static_cast<std::streamsize>(depth.size() * sizeof(double)));
    if (in.gcount() == static_cast<std::streamsize>(depth.size() * sizeof(double))) return depth;
  }
  const pr::LightTransmittanceReference reference(mesh);
  pb::Stopwatch clock;
  penumbra::parallel_for(depth.size(), 64, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) depth[i] = reference.optical_depth(scene.scalars, tf, light, mesh->points[i]);
  });
  std::cerr << "pnb_bench_light: reference light at " << depth.size() << " points in " << clock.ms() << " ms\n";
  std::filesystem::create_directories(dir + "/light-reference");
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary);
    out.write(reinterpret_cast<const char*>(depth.data()), static_cast<std::streamsize>(depth.size() * sizeof(double)));
    if (!out) throw penumbra::Error(penumbra::ErrorCode::io_error, "cannot write '" + tmp + "'");
  }
  std::filesystem::rename(tmp, path);
  return depth;
}

// A grey light field (3 per point) from one value per point; null: full light everywhere.
std::vector<float> grey(const std::vector<float>* rho, std::size_t points) {
  std::vector<float> rgb(3 * points, 1.0f);
  if (rho)
    for (std::size_t i = 0; i < points; ++i) rgb[3 * i] = rgb[3 * i + 1] = rgb[3 * i + 2] = (*rho)[i];
  return rgb;
}

int run(int argc, char** argv) {
  const std::string name = pb::option(argc, argv, "scene", "holeblock-1m");
  const std::string data_dir = pb::option(argc, argv, "data-dir", "");
  const int samples = std::stoi(pb::option(argc, argv, "samples", "4000"));
  const int frames = std::stoi(pb::option(argc, argv, "frames", "3"));
  std::vector<int> levels;
  {
    std::istringstream in(pb::option(argc, argv, "levels", "16 32 64 128 256"));
    for (int l; in >> l;) levels.push_back(l);
  }
  penumbra::require(!data_dir.empty(), "pnb_bench_light: --data-dir DIR is required");
  // Which lines to print: "sweep" (the Table 2 lines), "1m" (light-1m), "gpu" (light-1m on the
  // GPU, with "1m"), "budget" (light-budget).
  std::string parts = " ";
  parts += pb::option(argc, argv, "parts", "sweep 1m gpu budget");
  parts += " ";
  auto part = [&](const char* name) { return parts.find(std::string(" ") + name + " ") != std::string::npos; };

  const pb::Scene scene = pb::load_scene(name, data_dir);
  auto mesh = std::make_shared<const pr::TetMesh>(pr::prepare_tet_mesh(pb::mesh_view(scene), "bench"));
  const pr::TransferFunction tf = pb::transfer_function(scene);
  const std::vector<float>& scalars = scene.scalars;
  const pr::Light light{pr::Light::Kind::directional, {0.8, -0.45, -0.4}, {1, 1, 1}};

  // Sampled vertices (fixed seed) and their reference optical depth.
  std::vector<bool> used(mesh->points.size(), false);
  for (const auto& t : mesh->tets)
    for (auto v : t) used[static_cast<std::size_t>(v)] = true;
  std::vector<std::int32_t> pool;
  for (std::size_t p = 0; p < used.size(); ++p)
    if (used[p]) pool.push_back(static_cast<std::int32_t>(p));
  std::mt19937 rng(12345);
  std::shuffle(pool.begin(), pool.end(), rng);
  pool.resize(std::min<std::size_t>(pool.size(), static_cast<std::size_t>(samples)));
  const pr::LightTransmittanceReference reference(mesh);
  std::vector<double> depth(pool.size());
  pb::Stopwatch ref_clock;
  penumbra::parallel_for(pool.size(), 16, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i)
      depth[i] = reference.optical_depth(scalars, tf, light, mesh->points[static_cast<std::size_t>(pool[i])]);
  });
  const double ref_ms = ref_clock.ms();
  // The scene's transfer function is tuned for imaging; sigma_a is chosen so that the median
  // sampled vertex receives half the light, which makes shadows neither absent nor total.
  std::vector<double> sorted = depth;
  std::sort(sorted.begin(), sorted.end());
  const double median_depth = sorted[sorted.size() / 2];
  const double sigma_a = median_depth > 0 ? std::log(2.0) / median_depth : 1.0;
  std::vector<double> truth(depth.size());
  for (std::size_t i = 0; i < depth.size(); ++i) truth[i] = std::exp(-sigma_a * depth[i]);
  auto rms_pct = [&](const std::vector<float>* rho) {
    double sq = 0;
    for (std::size_t i = 0; i < pool.size(); ++i) {
      const double v = rho ? (*rho)[static_cast<std::size_t>(pool[i])] : 1.0;
      sq += (v - truth[i]) * (v - truth[i]);
    }
    return 100.0 * std::sqrt(sq / static_cast<double>(pool.size()));
  };
  std::cerr << "pnb_bench_light: " << mesh->tets.size() << " tets, " << pool.size() << " reference vertices in "
            << ref_ms << " ms, sigma_a " << sigma_a << "\n";

  // Image error: light-only shading (ambient 1), the same camera as the render benchmark.
  const int image_size = std::stoi(pb::option(argc, argv, "image-size", "256"));
  const pr::CpuRayCaster caster(mesh);
  const pr::Camera image_cam = pb::camera(scene, image_size, image_size);
  auto shaded_rgb = [&](const std::vector<float>& light_rgb) {
    pr::RenderOptions ro;
    ro.shading.model = pr::LightingModel::light_volume;
    ro.shading.light_rgb = &light_rgb;
    ro.shading.ambient = 1.0;
    ro.shading.diffuse = 0.0;
    ro.shading.specular = 0.0;
    return pr::to_rgb8(caster.render(scalars, tf, image_cam, ro), scene.background);
  };
  std::vector<unsigned char> reference_image;
  {
    const std::vector<double> all_depth = reference_depths(scene, mesh, tf, light, data_dir);
    std::vector<float> t(all_depth.size());
    for (std::size_t i = 0; i < t.size(); ++i) t[i] = static_cast<float>(std::exp(-sigma_a * all_depth[i]));
    reference_image = shaded_rgb(grey(&t, t.size()));
  }
  auto image_rms_pct = [&](const std::vector<float>* rho) {
    return pr::rms_difference_pct(shaded_rgb(grey(rho, mesh->points.size())), reference_image);
  };

  const double none_error = rms_pct(nullptr);
  const double none_image_error = image_rms_pct(nullptr);
  for (int level : part("sweep") ? levels : std::vector<int>{}) {
    {
      nlohmann::ordered_json line;
      line["bench"] = "light";
      line["scene"] = name;
      line["tets"] = mesh->tets.size();
      line["level0"] = level;
      line["mode"] = "none";
      for (const char* k : {"l0_prop_ms", "l0_scatter_ms", "l1_prop_ms", "l1_scatter_ms", "total_ms"}) line[k] = 0.0;
      line["rms_error_pct"] = pb::rounded(none_image_error, 3);
      line["vertex_rms_error_pct"] = pb::rounded(none_error, 3);
      line["image_size"] = image_size;
      std::cout << line.dump() << std::endl;
    }
    for (auto mode : {pr::LightSolveMode::level0_only, pr::LightSolveMode::two_level}) {
      pr::LightVolumeOptions opt;
      opt.level0_resolution = level;
      opt.level0_memory_budget_bytes = std::size_t{1} << 30;
      opt.sigma_a = sigma_a;
      opt.sigma_s = {1.0, 1.0, 1.0};
      opt.mode = mode;
      pb::Stopwatch build_clock;
      pr::LightVolume lv(mesh, opt);
      const double build_ms = build_clock.ms();
      // Median of `frames` full updates of a light that moved by 1 degree each time (as in the
      // paper's Table 1: the light's vertex order is rebuilt and every vertex walks again; after
      // the first update, each walk first tries its vertex's previous start tet), the last one
      // at the benchmark's light so the error is measured there.
      std::vector<pr::LightUpdateReport> reports;
      std::vector<double> totals, cpus;
      lv.set_field(scalars, tf);
      for (int f = frames - 1; f >= 0; --f) {
        lv.set_lights({moved(light, f)});
        const double c0 = cpu_ms();
        reports.push_back(lv.update());
        cpus.push_back(cpu_ms() - c0);
        totals.push_back(reports.back().total_ms);
      }
      const double median_total = pb::median(totals);
      const auto& r = *std::min_element(reports.begin(), reports.end(), [&](const auto& a, const auto& b) {
        return std::fabs(a.total_ms - median_total) < std::fabs(b.total_ms - median_total);
      });
      const auto dims = lv.level0_dims();
      nlohmann::ordered_json line;
      line["bench"] = "light";
      line["scene"] = name;
      line["tets"] = mesh->tets.size();
      line["level0"] = level;
      line["level0_dims"] = {dims[0], dims[1], dims[2]};
      line["mode"] = mode == pr::LightSolveMode::two_level ? "two-level" : "level0-only";
      line["resample_ms"] = pb::rounded(r.resample_ms, 1);
      line["l0_prop_ms"] = pb::rounded(r.l0_prop_ms, 1);
      line["l0_scatter_ms"] = pb::rounded(r.l0_scatter_ms, 1);
      line["l1_prop_ms"] = pb::rounded(r.l1_prop_ms, 1);
      line["l1_scatter_ms"] = pb::rounded(r.l1_scatter_ms, 1);
      line["total_ms"] = pb::rounded(r.total_ms, 1);
      line["cpu_ms"] = pb::rounded(pb::median(cpus), 1);
      line["build_ms"] = pb::rounded(build_ms, 1);
      line["level1_passes"] = r.level1_passes;
      line["scatter_iterations"] = r.scatter_iterations;
      line["converged"] = r.converged;
      line["rms_error_pct"] = pb::rounded(image_rms_pct(&lv.light_rho(0)), 3);
      line["vertex_rms_error_pct"] = pb::rounded(rms_pct(&lv.light_rho(0)), 3);
      line["image_size"] = image_size;
      line["sigma_a"] = pb::rounded(sigma_a, 4);
      line["threads"] = penumbra::worker_count();
      std::cout << line.dump() << std::endl;
    }
  }

  // The next in-situ time step's field: the same structure, values changed by up to 10 %.
  std::vector<float> next_step(scalars.size());
  for (std::size_t p = 0; p < scalars.size(); ++p) {
    const auto& x = mesh->points[p];
    next_step[p] = scalars[p] * static_cast<float>(1.0 + 0.1 * std::sin(3.0 * x.x + 2.0 * x.y));
  }

  // One full update of the default light volume (128^3, two levels, scattering) with one light:
  // after a new field and a light that moved by 1 degree (everything recomputed; each walk first
  // tries its vertex's previous start tet), the first of them on a new volume (no start tets to
  // try: first_total_ms), and warm (the next time step's field, same light: warm start, cached
  // vertex order and start tets, recorded walks).
  if (part("1m")) {
    pr::LightVolumeOptions opt;
    opt.sigma_a = sigma_a;
    opt.sigma_s = {1.0, 1.0, 1.0};
    pb::Stopwatch build_clock;
    pr::LightVolume lv(mesh, opt);
    const double build_ms = build_clock.ms();
    std::vector<double> cold, cold_cpu, warm, cold_no_scatter;
    for (int f = 0; f < frames; ++f) {
      lv.set_field(scalars, tf);
      lv.set_lights({moved(light, f + 1)});
      const double c0 = cpu_ms();
      cold.push_back(lv.update().total_ms);
      cold_cpu.push_back(cpu_ms() - c0);
      lv.set_field(next_step, tf);
      warm.push_back(lv.update().total_ms);
    }
    lv.set_scattering({0, 0, 0});
    for (int f = 0; f < frames; ++f) {
      lv.set_field(scalars, tf);
      lv.set_lights({moved(light, f + 1)});
      cold_no_scatter.push_back(lv.update().total_ms);
    }
    nlohmann::ordered_json line;
    line["bench"] = "light-1m";
    line["backend"] = "cpu";
    line["scene"] = name;
    line["tets"] = mesh->tets.size();
    line["level0"] = lv.level0_dims()[0];
    line["total_ms"] = pb::rounded(pb::median(cold), 1);
    line["first_total_ms"] = pb::rounded(cold.front(), 1);
    line["cpu_ms"] = pb::rounded(pb::median(cold_cpu), 1);
    line["total_ms_without_scattering"] = pb::rounded(pb::median(cold_no_scatter), 1);
    line["warm_total_ms"] = pb::rounded(pb::median(warm), 1);
    line["build_ms"] = pb::rounded(build_ms, 1);
    line["threads"] = penumbra::worker_count();
    line["target_ms"] = 1000;
    std::cout << line.dump() << std::endl;

    // The same cold update on the GPU; lv now holds the CPU's converged rho of the last light.
    if (part("gpu")) {
      const std::shared_ptr<pr::GpuDevice> device = pb::open_bench_gpu("pnb_bench_light");
      if (device) {
        pr::LightVolumeOptions gopt = opt;
        gopt.device = device;
        pb::Stopwatch gpu_build_clock;
        pr::LightVolume glv(mesh, gopt);
        const double gpu_build_ms = gpu_build_clock.ms();
        std::vector<double> gpu_cold, gpu_warm;
        pr::LightUpdateReport last;
        for (int f = 0; f < frames; ++f) {
          glv.set_field(scalars, tf);
          glv.set_lights({moved(light, f + 1)});
          last = glv.update();
          gpu_cold.push_back(last.total_ms);
          glv.set_field(next_step, tf);
          gpu_warm.push_back(glv.update().total_ms);
        }
        // Agreement: the last light on the CPU's field `scalars`, before scattering.
        glv.set_field(scalars, tf);
        glv.set_lights({moved(light, frames)});
        glv.update();
        double max_diff = 0, sum_diff = 0;
        std::size_t n = 0;
        for (std::size_t p = 0; p < used.size(); ++p) {
          if (!used[p]) continue;
          const double d = std::fabs(static_cast<double>(glv.light_rho(0)[p]) - lv.light_rho(0)[p]);
          max_diff = std::max(max_diff, d);
          sum_diff += d;
          ++n;
        }
        nlohmann::ordered_json g;
        g["bench"] = "light-1m";
        g["backend"] = "gpu";
        g["scene"] = name;
        g["tets"] = mesh->tets.size();
        g["level0"] = glv.level0_dims()[0];
        g["total_ms"] = pb::rounded(pb::median(gpu_cold), 1);
        g["warm_total_ms"] = pb::rounded(pb::median(gpu_warm), 1);
        g["l0_prop_ms"] = pb::rounded(last.l0_prop_ms, 1);
        g["l1_prop_ms"] = pb::rounded(last.l1_prop_ms, 1);
        g["l1_scatter_ms"] = pb::rounded(last.l1_scatter_ms, 1);
        g["resample_ms"] = pb::rounded(last.resample_ms, 1);
        g["level1_passes"] = last.level1_passes;
        g["scatter_iterations"] = last.scatter_iterations;
        g["build_ms"] = pb::rounded(gpu_build_ms, 1);
        g["max_abs_diff_vs_cpu"] = max_diff;
        g["mean_abs_diff_vs_cpu"] = n ? sum_diff / static_cast<double>(n) : 0.0;
        g["speedup_vs_cpu"] = pb::rounded(pb::median(cold) / std::max(1e-9, pb::median(gpu_cold)), 2);
        g["device"] = device->info().gl_renderer;
        g["software"] = device->info().software;
        std::cout << g.dump() << std::endl;
      }
    }
  }

  // Per-frame budget: a share of one CPU render frame (--budget-pct, default 8 %: a piece that
  // starts within the budget may overrun it by a little, and the frame must slow by under 10 %).
  // The frame is the one a lit run renders: shaded by a light field (median of three). Two
  // starts: "cold" (a new light volume: every stage from nothing), "time-step" (the next step's
  // field with the same light, warm-started from the converged light of this step) and
  // "light-moved" (the light turned by 5 degrees: the level-1 walks start over).
  if (part("budget")) {
    const pr::CpuRayCaster caster(mesh);
    const pr::Camera cam = pb::camera(scene);
    const std::vector<float> unit_light(3 * mesh->points.size(), 1.0f);
    pr::RenderOptions lit;
    lit.shading.model = pr::LightingModel::light_volume;
    lit.shading.light_rgb = &unit_light;
    std::vector<double> frame_times;
    for (int f = 0; f < 3; ++f) {
      pb::Stopwatch render_clock;
      (void)caster.render(scalars, tf, cam, lit);
      frame_times.push_back(render_clock.ms());
    }
    const double frame_ms = pb::median(frame_times);
    const double budget_pct = std::stod(pb::option(argc, argv, "budget-pct", "8"));
    pr::LightVolumeOptions opt;
    opt.sigma_a = sigma_a;
    opt.sigma_s = {1.0, 1.0, 1.0};
    pb::Stopwatch build_clock;
    pr::LightVolume lv(mesh, opt);
    const double build_ms = build_clock.ms();
    lv.set_lights({light});
    lv.set_field(scalars, tf);
    pr::LightBudget budget;
    budget.max_ms = budget_pct / 100.0 * frame_ms;
    auto run_frames = [&](const char* start) {
      int frames_to_converge = 0;
      double worst_ms = 0;
      for (; frames_to_converge < 1000; ++frames_to_converge) {
        const auto r = lv.update(budget);
        worst_ms = std::max(worst_ms, r.total_ms);
        if (std::getenv("PNB_BENCH_LIGHT_VERBOSE"))
          std::cerr << start << " frame " << frames_to_converge << ": " << r.total_ms << " ms (resample "
                    << r.resample_ms << ", l0 " << r.l0_prop_ms << ", l1 " << r.l1_prop_ms << ", scatter "
                    << r.l1_scatter_ms << ", passes " << r.level1_passes << ", iterations " << r.scatter_iterations << ", residual " << r.residual << ")\n";
        if (r.converged) {
          ++frames_to_converge;
          break;
        }
      }
      nlohmann::ordered_json line;
      line["bench"] = "light-budget";
      line["scene"] = name;
      line["start"] = start;
      line["tets"] = mesh->tets.size();
      line["frame_ms"] = pb::rounded(frame_ms, 1);
      line["budget_pct"] = budget_pct;
      line["budget_ms"] = pb::rounded(budget.max_ms, 1);
      line["frames_to_converge"] = frames_to_converge;
      // A cold start's volume is built before its first frame, once per mesh, outside every
      // frame's budget (it also prepares the first light's memory and timings): shown beside it.
      if (std::string(start) == "cold") line["build_ms"] = pb::rounded(build_ms, 1);
      // The light solve's share of the worst frame.
      line["frame_slowdown_pct"] = pb::rounded(100.0 * worst_ms / frame_ms, 1);
      line["threads"] = penumbra::worker_count();
      line["target_frames"] = 10;
      line["target_slowdown_pct"] = 10;
      std::cout << line.dump() << std::endl;
    };
    run_frames("cold");
    lv.set_field(next_step, tf);
    run_frames("time-step");
    // A scientist turning the light: every walk again, in the storage the last ones left.
    lv.set_lights({moved(light, 5)});
    run_frames("light-moved");
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return penumbra::bench::guarded_main("pnb_bench_light", run, argc, argv); }

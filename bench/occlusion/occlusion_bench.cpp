// SPDX-License-Identifier: BSD-3-Clause
// bench/occlusion/occlusion_bench.cpp -- cone-traced directional occlusion and shadows: speed of a
// frame beside its error against the Monte Carlo image (thesis tables 3.3-3.6 in spirit).
//
// Usage: pnb_bench_occlusion --scene NAME [--data-dir DIR] [--test-data DIR] [--frames N] [--size WxH]
//          [--grid N] [--preillum N] [--mc-max-points N] [--hex-n N] [--alpha A] [--weight mean|thesis]
//          [--level continuous|thesis]
//          [--pyramid opacity|extinction|step_opacity] [--image-space on|off] [--gpu on|off]
//          [--modes all|shadow]  (shadow: only ao+shadow and the hard-shadow lines)
// Scenes: hexblock-hole (procedural hexahedra with a through-hole, split into tets on
// preparation), plate-shadow (hexahedra, an opaque plate over fog: hard shadow edges),
// disk-out-ref (the hexahedra of tests/data/disk_out_ref.ex2, --test-data DIR),
// grid-aligned and holeblock-1m (bench/render's scenes, about 1M tets), holeblock-100k (the same
// graded hole-block at about 98K tets, small enough for Monte Carlo).
//
// Every mode renders colour(s) x L(x) with L per mesh point, interpolated by the CPU ray caster
// (LightingModel::light_volume with ambient 1, no diffuse or specular, so the image differs from
// the emission-absorption one only by L). L is
//   ao-points:  the cone transparency towards the eye at every mesh point (image-space evaluation
//               per point; per-sample evaluation needs the renderer to call it),
//   ao-object:  the same, precomputed on a pre-illumination volume and sampled at the points,
//   ao-image:   the same cones traced at every segment end of every ray (scenes up to 200k tets;
//               --image-space off leaves it out: it costs seconds per frame),
//   ao+shadow:  ao-object times a 2-degree cone towards a directional light per point, its gap
//               integrated exactly (GapDepth), as the in-situ path lights it,
// and the Monte Carlo image uses converged cosine-weighted rays per point for the same cones
// (the shadow's rays from the point itself).
// Hard shadows, against the image lit by the exact single-ray transmittance to the light:
//   shadow-cone:          a 2-degree cone (splits 1) as long as the bounds' diagonal, its gap of
//                         3 sigma0 integrated exactly through the tets (GapDepth),
//   shadow-light-volume:  the two-level light volume (level 0 at 128) solved to convergence,
//   shadow-light-volume-level0:  its level 0 alone, interpolated to the points,
//   shadow-cone-image / shadow-light-volume-image: against the exact shadow per sample (every
//                         segment end of every ray) instead: the cone traced there, the light
//                         volume as it renders (image space on, scenes up to 200k tets).
// ms_per_frame includes recomputing L (AO follows the viewer), not the pyramid (per transfer
// function, reported as pyramid_build_ms). Errors are over pixels the mesh covers.
//
// Every line has "backend". With the GPU backend (--gpu on, the default; a hardware device or
// Mesa's llvmpipe) the modes ao-points, ao-object (splits 1/3/7) and shadow-cone are repeated with
// backend "gpu": L from GpuConeTracer (the pyramid filtered on the CPU and uploaded once per
// transfer function: pyramid_upload_ms), the frame from GpuRayCaster, and beside the errors
// against Monte Carlo the agreement with the CPU line of the same mode: max_abs_diff_vs_cpu
// (|L_gpu - L_cpu| over the mesh points, with the mean and the count above 1e-4) and
// image_rms_vs_cpu_pct (the two frames, % of 255);
// light_ms is the cone tracing alone (dispatches and read-back of L), within ms_per_frame.
// pyramid_gpu_build_ms / pyramid_gpu_filter_ms: the same pyramid filtered on the device (all of
// it, and the passes alone), beside pyramid_build_ms of the CPU.
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <iostream>
#include <map>
#include <memory>
#include <optional>

#include "bench_util.h"
#include "exodus_mesh.h"
#include "penumbra/core/error.h"
#include "penumbra/core/thread_pool.h"
#include "penumbra/render/cpu_ray_caster.h"
#include "occlusion/gpu_occlusion.h"
#include "penumbra/render/gpu_ray_caster.h"
#include "penumbra/render/image.h"
#include "penumbra/render/light_volume.h"
#include "occlusion/occlusion_internals.h"
#include "scene.h"
#include "scene_views.h"

namespace pb = penumbra::bench;
namespace pr = penumbra::render;
using penumbra::Vec3d;

namespace {

struct Setup {
  std::string name;
  std::shared_ptr<const pr::TetMesh> mesh;
  std::vector<float> scalars;
  pr::TransferFunction tf;
  pr::Camera camera;
  float background[3] = {0.2f, 0.2f, 0.25f};
};

// n^3 hexahedra on [0,1]^3. hexblock-hole: a square through-hole along z in the middle third of
// x and y and a smooth field through a semi-transparent transfer function. plate-shadow: no hole,
// a thin opaque plate (about two cells thick) above thin fog, for hard shadow edges.
Setup hexblock(int n, int width, int height, bool plate) {
  std::vector<double> xyz;
  const int m = n + 1;
  for (int k = 0; k < m; ++k)
    for (int j = 0; j < m; ++j)
      for (int i = 0; i < m; ++i) {
        xyz.push_back(static_cast<double>(i) / n);
        xyz.push_back(static_cast<double>(j) / n);
        xyz.push_back(static_cast<double>(k) / n);
      }
  auto id = [m](int i, int j, int k) { return (static_cast<std::int64_t>(k) * m + j) * m + i; };
  std::vector<std::int64_t> conn;
  const int a = n / 3, b = n - n / 3;
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        if (!plate && i >= a && i < b && j >= a && j < b) continue;
        const std::int64_t v[8] = {id(i, j, k),         id(i + 1, j, k),         id(i + 1, j + 1, k),
                                   id(i, j + 1, k),     id(i, j, k + 1),         id(i + 1, j, k + 1),
                                   id(i + 1, j + 1, k + 1), id(i, j + 1, k + 1)};
        conn.insert(conn.end(), v, v + 8);
      }
  static const std::uint8_t hexahedron = 12;
  penumbra::MeshView view;
  view.points = {reinterpret_cast<const std::byte*>(xyz.data()), xyz.size() / 3, 3 * sizeof(double)};
  view.point_type = penumbra::ScalarType::float64;
  view.connectivity = {conn.data(), conn.size(), penumbra::ScalarType::int64};
  view.cell_types = &hexahedron;
  view.cell_type_count = 1;
  view.topology_version = 1;
  Setup s;
  s.name = plate ? "plate-shadow" : "hexblock-hole";
  s.mesh = std::make_shared<const pr::TetMesh>(pr::prepare_tet_mesh(view, "bench"));
  s.scalars.resize(s.mesh->points.size());
  for (std::size_t p = 0; p < s.scalars.size(); ++p) {
    const Vec3d& x = s.mesh->points[p];
    if (plate) {
      const bool in_plate = std::fabs(x.z - 0.72) <= 1.01 / n && std::fabs(x.x - 0.5) <= 0.2 && std::fabs(x.y - 0.5) <= 0.2;
      s.scalars[p] = in_plate ? 1.0f : static_cast<float>(0.3 + 0.1 * std::sin(7 * x.x + 3 * x.y));
    } else {
      s.scalars[p] = static_cast<float>(0.5 + 0.3 * std::sin(5 * x.x) * std::cos(4 * x.y) + 0.2 * std::cos(6 * x.z));
    }
  }
  if (plate) {
    s.tf.colors = {{0.0, 0.9, 0.9, 0.9}, {0.5, 0.8, 0.85, 1.0}, {1.0, 0.9, 0.5, 0.2}};
    s.tf.opacities = {{0.0, 0.0}, {0.5, 1.5}, {0.9, 200.0}};
  } else {
    s.tf.colors = {{0.0, 0.2, 0.4, 0.9}, {0.5, 0.9, 0.9, 0.8}, {1.0, 0.9, 0.3, 0.1}};
    s.tf.opacities = {{0.0, 0.0}, {0.45, 0.5}, {0.6, 25.0}, {0.75, 4.0}, {1.0, 10.0}};
  }
  s.camera = pr::Camera::look_at({2.4, -1.6, 2.2}, {0.5, 0.5, 0.5}, {0, 0, 1}, 30.0, width, height);
  return s;
}

// disk-out-ref: ParaView's "disk_out_ref" example from tests/data (7472 hexahedra of a
// cylindrical reactor around a spinning disk, split into tets on preparation), its temperature
// normalised to [0, 1] through a semi-transparent transfer function, seen obliquely.
Setup disk_out_ref(const std::string& test_data_dir, int width, int height) {
  const pb::HexMesh hm = pb::read_exodus_hexes(test_data_dir + "/disk_out_ref.ex2", "Temp");
  static const std::uint8_t hexahedron = 12;
  penumbra::MeshView view;
  view.points = {reinterpret_cast<const std::byte*>(hm.points.data()), hm.points.size() / 3, 3 * sizeof(double)};
  view.point_type = penumbra::ScalarType::float64;
  view.connectivity = {hm.hexes.data(), hm.hexes.size(), penumbra::ScalarType::int64};
  view.cell_types = &hexahedron;
  view.cell_type_count = 1;
  view.topology_version = 1;
  Setup s;
  s.name = "disk-out-ref";
  s.mesh = std::make_shared<const pr::TetMesh>(pr::prepare_tet_mesh(view, "bench"));
  const auto [lo, hi] = std::minmax_element(hm.field.begin(), hm.field.end());
  s.scalars.resize(hm.field.size());
  for (std::size_t p = 0; p < s.scalars.size(); ++p) s.scalars[p] = (hm.field[p] - *lo) / (*hi - *lo);
  // Extinction per world unit (the mesh is about 20 units long): the hot core near the disk is
  // the densest, the cold gas nearly clear.
  s.tf.colors = {{0.0, 0.2, 0.4, 0.9}, {0.5, 0.9, 0.9, 0.8}, {1.0, 0.9, 0.3, 0.1}};
  s.tf.opacities = {{0.0, 0.0}, {0.2, 0.1}, {0.5, 0.75}, {0.7, 3.0}, {0.85, 1.0}, {1.0, 2.0}};
  s.camera = pr::Camera::look_at({30.0, -22.0, 18.0}, {0.0, 0.0, 0.0}, {0, 0, 1}, 30.0, width, height);
  return s;
}

Setup bench_scene(const std::string& name, const std::string& data_dir, int width, int height) {
  const pb::Scene sc = pb::load_scene(name, data_dir);
  Setup s;
  s.name = sc.name;
  s.mesh = std::make_shared<const pr::TetMesh>(pr::prepare_tet_mesh(pb::mesh_view(sc), "bench"));
  s.scalars = sc.scalars;
  s.tf = pb::transfer_function(sc);
  s.camera = pb::camera(sc, width, height);
  std::copy(sc.background, sc.background + 3, s.background);
  return s;
}

// CIELAB (D65) of an 8-bit sRGB triple.
void lab(const unsigned char* rgb, double out[3]) {
  double c[3];
  for (int i = 0; i < 3; ++i) {
    const double v = rgb[i] / 255.0;
    c[i] = v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4);
  }
  const double X = (0.4124 * c[0] + 0.3576 * c[1] + 0.1805 * c[2]) / 0.95047;
  const double Y = 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];
  const double Z = (0.0193 * c[0] + 0.1192 * c[1] + 0.9505 * c[2]) / 1.08883;
  auto f = [](double t) { return t > 216.0 / 24389 ? std::cbrt(t) : (24389.0 / 27 * t + 16) / 116; };
  out[0] = 116 * f(Y) - 16;
  out[1] = 500 * (f(X) - f(Y));
  out[2] = 200 * (f(Y) - f(Z));
}

struct ImageDiff {
  double delta_e_mean = 0, delta_e_p95 = 0, rms_pct = 0;
};

// CIE76 Delta E and RMS (% of 255) over pixels where either image has coverage.
ImageDiff compare(const pr::Image& a, const pr::Image& b, const float background[3]) {
  const auto ra = pr::to_rgb8(a, background), rb = pr::to_rgb8(b, background);
  std::vector<double> de;
  double sq = 0;
  for (std::size_t p = 0; p < a.rgba.size() / 4; ++p) {
    if (a.rgba[4 * p + 3] < 1e-3f && b.rgba[4 * p + 3] < 1e-3f) continue;
    double la[3], lb[3];
    lab(&ra[3 * p], la);
    lab(&rb[3 * p], lb);
    de.push_back(std::sqrt((la[0] - lb[0]) * (la[0] - lb[0]) + (la[1] - lb[1]) * (la[1] - lb[1]) + (la[2] - lb[2]) * (la[2] - lb[2])));
    for (int c = 0; c < 3; ++c) sq += std::pow((ra[3 * p + c] - rb[3 * p + c]) / 255.0, 2);
  }
  ImageDiff d;
  if (de.empty()) return d;
  double sum = 0;
  for (double v : de) sum += v;
  d.delta_e_mean = sum / de.size();
  std::sort(de.begin(), de.end());
  d.delta_e_p95 = de[std::min(de.size() - 1, static_cast<std::size_t>(0.95 * de.size()))];
  d.rms_pct = 100.0 * std::sqrt(sq / (3.0 * de.size()));
  return d;
}

int run(int argc, char** argv) {
  const std::string name = pb::option(argc, argv, "scene", "hexblock-hole");
  const std::string data_dir = pb::option(argc, argv, "data-dir", "");
  const std::string test_data_dir = pb::option(argc, argv, "test-data", "tests/data");
  const int frames = std::stoi(pb::option(argc, argv, "frames", "5"));
  const std::string size = pb::option(argc, argv, "size", "512x512");
  const int grid_res = std::stoi(pb::option(argc, argv, "grid", "128"));
  const int preillum_res = std::stoi(pb::option(argc, argv, "preillum", "64"));
  const std::size_t mc_max_points = std::stoul(pb::option(argc, argv, "mc-max-points", "60000"));
  // Monte Carlo rays per cone double until two successive estimates differ by less than this.
  const double mc_tolerance = std::stod(pb::option(argc, argv, "mc-tolerance", "5e-3"));
  const int mc_max_rays = std::stoi(pb::option(argc, argv, "mc-max-rays", "1024"));
  const int hex_n = std::stoi(pb::option(argc, argv, "hex-n", "24"));
  const double alpha = std::stod(pb::option(argc, argv, "alpha", "1"));
  const std::string weight_name = pb::option(argc, argv, "weight", "mean");
  const std::string pyramid_name = pb::option(argc, argv, "pyramid", "opacity");
  const std::string level_name = pb::option(argc, argv, "level", "continuous");
  penumbra::require(level_name == "continuous" || level_name == "thesis",
                    "pnb_bench_occlusion: --level " + level_name + "; expected continuous or thesis");
  penumbra::require(pyramid_name == "opacity" || pyramid_name == "extinction" || pyramid_name == "step_opacity",
                    "pnb_bench_occlusion: --pyramid " + pyramid_name + "; expected opacity, extinction or step_opacity");
  pr::PyramidOptions pyramid_options;
  pyramid_options.quantity = pyramid_name == "opacity"      ? pr::PyramidQuantity::opacity
                             : pyramid_name == "extinction" ? pr::PyramidQuantity::extinction
                                                            : pr::PyramidQuantity::step_opacity;
  const std::string gpu_option = pb::option(argc, argv, "gpu", "on");
  const std::string image_space = pb::option(argc, argv, "image-space", "on");
  const std::string modes = pb::option(argc, argv, "modes", "all");
  penumbra::require(modes == "all" || modes == "shadow", "pnb_bench_occlusion: --modes " + modes + "; expected all or shadow");
  penumbra::require(image_space == "on" || image_space == "off",
                    "pnb_bench_occlusion: --image-space " + image_space + "; expected on or off");
  penumbra::require(gpu_option == "on" || gpu_option == "off", "pnb_bench_occlusion: --gpu " + gpu_option + "; expected on or off");
  penumbra::require(weight_name == "mean" || weight_name == "thesis",
                    "pnb_bench_occlusion: --weight " + weight_name + "; expected mean or thesis");
  const pr::SectionWeight weight = weight_name == "mean" ? pr::SectionWeight::mean : pr::SectionWeight::thesis;
  // Occlusion cones as configured (alpha and the section weight apply to every cone).
  auto cone = [&](double aperture, int splits, bool shadow) {
    pr::ConeOptions o = shadow ? pr::ConeOptions::shadow(aperture, splits) : pr::ConeOptions::occlusion(aperture, splits);
    // alpha calibrates the occlusion cones' darkening (Jensen bias of wide sections); narrow
    // shadow cones keep alpha = 1.
    if (!shadow) o.attenuation = alpha;
    o.weight = weight;
    o.level = level_name == "thesis" ? pr::LevelSelection::thesis : pr::LevelSelection::continuous;
    return o;
  };
  int width = 512, height = 512;
  penumbra::require(std::sscanf(size.c_str(), "%dx%d", &width, &height) == 2 && width > 0 && height > 0,
                    "pnb_bench_occlusion: --size " + size + "; expected WxH");
  penumbra::require(frames >= 1, "pnb_bench_occlusion: --frames must be >= 1");

  const Setup s = name == "hexblock-hole" || name == "plate-shadow" ? hexblock(hex_n, width, height, name == "plate-shadow")
                  : name == "disk-out-ref"                            ? disk_out_ref(test_data_dir, width, height)
                                                                      : bench_scene(name, data_dir, width, height);
  const pr::TetMesh& mesh = *s.mesh;
  const pr::CpuRayCaster caster(s.mesh);
  const Vec3d eye = s.camera.eye;
  const pr::ShadowLight sun{pr::ShadowLight::Kind::directional, {-0.4, 0.3, -1.0}};
  constexpr double kAperture = 20.0, kShadowAperture = 2.0;

  // Pyramid: rebuilt on every transfer-function change; timed on its own.
  pb::Stopwatch resample_clock;
  const pr::ExtinctionGrid grid = pr::resample_extinction(mesh, s.scalars, s.tf, grid_res);
  const double resample_ms = resample_clock.ms();
  const pr::ExtinctionPyramid pyramid(grid, pyramid_options);

  pr::RenderOptions lit;
  lit.shading.model = pr::LightingModel::light_volume;
  lit.shading.ambient = 1.0;
  lit.shading.diffuse = 0.0;
  lit.shading.specular = 0.0;
  auto render_with = [&](const std::vector<float>& rgb) {
    pr::RenderOptions o = lit;
    o.shading.light_rgb = &rgb;
    return caster.render(s.scalars, s.tf, s.camera, o);
  };

  // Monte Carlo light fields (per point, same cones), when the scene is small enough.
  const bool with_mc = mesh.points.size() <= mc_max_points;
  std::vector<float> mc_ao, mc_shadow;
  double mc_ms = 0, mc_rays = 0;
  pr::Image mc_ao_image, mc_both_image;
  const pr::ConeTracer ao3(pyramid, cone(kAperture, 3, false));
  const pr::ConeTracer shadow1(pyramid, cone(kShadowAperture, 1, true));
  // Shadows are the light that reaches x: the cones' gap is integrated exactly through the tets
  // (per transfer function, like the pyramid), and the Monte Carlo rays start at the point.
  pr::GapDepth gap_depth(s.mesh);
  gap_depth.set_field(s.scalars, s.tf);
  if (with_mc) {
    pb::Stopwatch mc_clock;
    const pr::ConeMonteCarlo mc(s.mesh, s.scalars, s.tf);
    std::vector<double> rays(mesh.points.size(), 0.0);
    auto mc_field = [&](bool shadow) {
      std::vector<float> out(mesh.points.size(), 1.0f);
      penumbra::parallel_for(out.size(), 64, [&](std::size_t p0, std::size_t p1) {
        for (std::size_t p = p0; p < p1; ++p) {
          const Vec3d& x = mesh.points[p];
          const pr::MonteCarloResult r =
              shadow ? mc.transmittance(x, -sun.vector, kShadowAperture, 0.0, shadow1.length(), mc_tolerance,
                                        32, mc_max_rays, p)
                     : mc.transmittance(x, eye - x, kAperture, ao3.gap(), ao3.length(), mc_tolerance, 32, mc_max_rays, p);
          out[p] = static_cast<float>(r.transmittance);
          rays[p] += r.rays;
        }
      });
      return out;
    };
    mc_ao = mc_field(false);
    mc_shadow = mc_field(true);
    for (double r : rays) mc_rays += r;
    mc_rays /= 2.0 * rays.size();
    mc_ms = mc_clock.ms();
    std::vector<float> both(mc_ao.size());
    for (std::size_t p = 0; p < both.size(); ++p) both[p] = mc_ao[p] * mc_shadow[p];
    mc_ao_image = render_with(pr::grey_light_rgb(mc_ao));
    mc_both_image = render_with(pr::grey_light_rgb(both));
  }

  auto emit = [&](const std::string& mode, int splits, const std::vector<double>& times, const pr::Image& image,
                  const pr::Image* reference, const nlohmann::ordered_json& extra = {}) {
    nlohmann::ordered_json line;
    line["bench"] = "occlusion";
    line["backend"] = "cpu";
    line["scene"] = s.name;
    line["tets"] = mesh.tet_count();
    line["points"] = mesh.points.size();
    line["mode"] = mode;
    line["splits"] = splits;
    line["aperture_deg"] = mode.rfind("ao", 0) == 0 ? kAperture : 0.0;
    line["shadow_aperture_deg"] = mode == "ao+shadow" || mode.rfind("shadow-cone", 0) == 0 ? kShadowAperture : 0.0;
    line["alpha"] = alpha;
    line["section_weight"] = weight_name;
    line["pyramid_quantity"] = pyramid_name;
    line["level_selection"] = level_name;
    line["width"] = width;
    line["height"] = height;
    line["ms_per_frame"] = pb::rounded(pb::median(times));
    line["pyramid_build_ms"] = pb::rounded(pyramid.build_ms());
    line["resample_ms"] = pb::rounded(resample_ms);
    line["grid"] = grid.dims;
    line["preillum"] = mode == "ao-object" || mode == "ao+shadow" ? preillum_res : 0;
    if (reference) {
      const ImageDiff d = compare(image, *reference, s.background);
      line["delta_e_mean"] = pb::rounded(d.delta_e_mean);
      line["delta_e_p95"] = pb::rounded(d.delta_e_p95);
      line["rms_error_pct"] = pb::rounded(d.rms_pct);
      line["mc_rays_mean"] = pb::rounded(mc_rays, 1);
      line["mc_ms"] = pb::rounded(mc_ms, 1);
    } else {
      line["delta_e_mean"] = nullptr;
      line["delta_e_p95"] = nullptr;
      line["rms_error_pct"] = nullptr;
    }
    line["threads"] = penumbra::worker_count();
    line["load_avg"] = pb::load_average();
    for (const auto& [key, value] : extra.items()) line[key] = value;
    std::cout << line.dump() << std::endl;
  };
  auto timed = [&](const std::function<pr::Image()>& frame, pr::Image& last) {
    last = frame();  // warm-up
    std::vector<double> times;
    for (int f = 0; f < frames; ++f) {
      pb::Stopwatch clock;
      last = frame();
      times.push_back(clock.ms());
    }
    return times;
  };

  pr::Image image;
  // Emission-absorption: the frame every lit mode is compared with (speed), and how far the
  // unlit image is from the Monte Carlo one (what occlusion adds).
  std::vector<double> t;
  if (modes == "all") {
    t = timed([&] { return caster.render(s.scalars, s.tf, s.camera); }, image);
    emit("emission-absorption", 0, t, image, with_mc ? &mc_ao_image : nullptr);
  }

  // The CPU's L and frame per mode and splits, for the GPU lines' agreement.
  std::map<std::string, std::pair<std::vector<float>, pr::Image>> cpu_result;
  auto key = [](const std::string& mode, int splits) { return mode + "/" + std::to_string(splits); };
  for (int splits : {1, 3, 7}) {
    if (modes != "all") break;
    const pr::ConeTracer tracer(pyramid, cone(kAperture, splits, false));
    auto ao = [&](const Vec3d& x) { return pr::directional_occlusion(tracer, x, eye); };
    std::vector<float> field;
    t = timed([&] { field = pr::evaluate_at_points(mesh, ao); return render_with(pr::grey_light_rgb(field)); }, image);
    emit("ao-points", splits, t, image, with_mc ? &mc_ao_image : nullptr);
    cpu_result[key("ao-points", splits)] = {field, image};
    t = timed(
        [&] {
          const pr::PreIlluminationVolume vol(pyramid.bounds(), preillum_res, ao);
          field = pr::evaluate_at_points(mesh, [&](const Vec3d& x) { return vol.sample(x); });
          return render_with(pr::grey_light_rgb(field));
        },
        image);
    emit("ao-object", splits, t, image, with_mc ? &mc_ao_image : nullptr);
    cpu_result[key("ao-object", splits)] = {field, image};
    // Image space: the cones traced at every segment end of every ray (a cone per tet step, so
    // only on the smaller scenes).
    if (image_space == "on" && mesh.tets.size() <= 200000) {
      t = timed(
          [&] {
            pr::RenderOptions o = lit;
            o.shading.light_at = [&](const Vec3d& x, double rgb[3]) { rgb[0] = rgb[1] = rgb[2] = ao(x); };
            return caster.render(s.scalars, s.tf, s.camera, o);
          },
          image);
      emit("ao-image", splits, t, image, with_mc ? &mc_ao_image : nullptr);
    }
  }
  // As the in-situ path lights it: occlusion through the pre-illumination volume, shadows per
  // point (a shadow edge would blur over a volume cell).
  t = timed(
      [&] {
        const pr::PreIlluminationVolume vol(pyramid.bounds(), preillum_res,
                                            [&](const Vec3d& x) { return pr::directional_occlusion(ao3, x, eye); });
        return render_with(pr::grey_light_rgb(pr::evaluate_at_points(
            mesh, [&](const Vec3d& x) { return vol.sample(x) * pr::shadow_transmittance(shadow1, sun, x, gap_depth); })));
      },
      image);
  emit("ao+shadow", 3, t, image, with_mc ? &mc_both_image : nullptr);
  // Hard shadows: a narrow cone and the light volume against the exact transmittance.
  const pr::Light light{pr::Light::Kind::directional, sun.vector, {1, 1, 1}};
  pr::Image hard_image;
  std::optional<pr::LightTransmittanceReference> reference;
  auto exact_shadow = [&](const Vec3d& x) { return reference->transmittance(s.scalars, s.tf, 1.0, light, x); };
  if (with_mc) {
    reference.emplace(s.mesh);
    hard_image = render_with(pr::grey_light_rgb(pr::evaluate_at_points(mesh, exact_shadow)));
  }
  pr::ConeOptions narrow = cone(kShadowAperture, 1, true);
  narrow.length = pyramid.bounds().diagonal();  // the whole mesh, like the reference ray
  const pr::ConeTracer shadow_cone(pyramid, narrow);
  {
    std::vector<float> field;
    t = timed([&] {
      field = pr::evaluate_at_points(mesh, [&](const Vec3d& x) { return pr::shadow_transmittance(shadow_cone, sun, x, gap_depth); });
      return render_with(pr::grey_light_rgb(field));
    }, image);
    emit("shadow-cone", 1, t, image, with_mc ? &hard_image : nullptr);
    cpu_result[key("shadow-cone", 1)] = {field, image};
  }
  pr::LightVolumeOptions lv_options;
  lv_options.level0_resolution = 128;
  pr::LightVolume volume(s.mesh, lv_options);
  volume.set_lights({light});
  pr::Image volume_image;
  const std::vector<double> volume_times = timed([&] {
    volume.set_field(s.scalars, s.tf);  // a full re-solve each frame, like a moving light
    volume.update();
    return render_with(volume.light_rgb());
  }, volume_image);
  emit("shadow-light-volume", 0, volume_times, volume_image, with_mc ? &hard_image : nullptr);
  // Level 0 alone (the upwind grid, interpolated to the points): the light volume without the
  // per-vertex trace-backs of level 1.
  lv_options.mode = pr::LightSolveMode::level0_only;
  pr::LightVolume coarse(s.mesh, lv_options);
  coarse.set_lights({light});
  t = timed([&] {
    coarse.set_field(s.scalars, s.tf);
    coarse.update();
    return render_with(coarse.light_rgb());
  }, image);
  emit("shadow-light-volume-level0", 0, t, image, with_mc ? &hard_image : nullptr);

  // The same shadows per sample: the exact transmittance at every segment end of every ray (not
  // interpolated from the mesh points) against the cone traced there and the light volume's light
  // (per point, as it renders). Where a shadow edge crosses a cell, the per-point reference above
  // smooths it exactly as the light volume does; this one does not.
  if (image_space == "on" && with_mc && mesh.tets.size() <= 200000) {
    pr::RenderOptions per_sample = lit;
    per_sample.shading.light_at = [&](const Vec3d& x, double rgb[3]) { rgb[0] = rgb[1] = rgb[2] = exact_shadow(x); };
    const pr::Image exact_image = caster.render(s.scalars, s.tf, s.camera, per_sample);
    per_sample.shading.light_at = [&](const Vec3d& x, double rgb[3]) {
      rgb[0] = rgb[1] = rgb[2] = pr::shadow_transmittance(shadow_cone, sun, x, gap_depth);
    };
    t = timed([&] { return caster.render(s.scalars, s.tf, s.camera, per_sample); }, image);
    emit("shadow-cone-image", 1, t, image, &exact_image);
    // The light volume renders the same way whatever it is compared with.
    emit("shadow-light-volume-image", 0, volume_times, volume_image, &exact_image);
  }

  // The GPU path: the same modes with the cones traced and the frame rendered on the device.
  const std::shared_ptr<pr::GpuDevice> device =
      gpu_option == "on" ? pb::open_bench_gpu("pnb_bench_occlusion") : nullptr;
  if (!device) return 0;
  const pr::GpuExtinctionPyramid gpu_pyramid(device, pyramid);
  // The same pyramid filtered on the device (second build timed: the first JIT-compiles the shader
  // on some drivers). The cones below still read the CPU-built levels (see gpu_occlusion.h).
  pr::gpu_build_pyramid_levels(device, grid, pyramid_options);
  const pr::GpuPyramidLevels gpu_levels = pr::gpu_build_pyramid_levels(device, grid, pyramid_options);
  pr::GpuRayCaster gpu_caster(device, s.mesh);
  auto gpu_frame = [&](const std::vector<float>& field) {
    const std::vector<float> rgb = pr::grey_light_rgb(field);
    pr::RenderOptions o = lit;
    o.shading.light_rgb = &rgb;
    return gpu_caster.render(s.scalars, s.tf, s.camera, o);
  };
  // L on the device alone (dispatches and read-back), per timed frame.
  std::vector<double> light_times;
  auto traced = [&](const std::function<std::vector<float>()>& trace) {
    pb::Stopwatch clock;
    std::vector<float> field = trace();
    light_times.push_back(clock.ms());
    return field;
  };
  auto emit_gpu = [&](const std::string& mode, int splits, const std::vector<double>& times, const std::vector<float>& field,
                      const pr::Image& frame, const pr::Image* reference) {
    const auto& [cpu_field, cpu_image] = cpu_result.at(key(mode, splits));
    double max_diff = 0, sum_diff = 0;
    std::size_t over = 0;
    for (std::size_t p = 0; p < field.size(); ++p) {
      const double d = std::fabs(static_cast<double>(field[p]) - cpu_field[p]);
      max_diff = std::max(max_diff, d);
      sum_diff += d;
      over += d > 1e-4 ? 1 : 0;
    }
    nlohmann::ordered_json extra;
    extra["backend"] = "gpu";
    extra["light_ms"] = pb::rounded(pb::median(light_times));
    extra["pyramid_built_on"] = "cpu";
    extra["pyramid_upload_ms"] = pb::rounded(gpu_pyramid.upload_ms());
    extra["pyramid_gpu_build_ms"] = pb::rounded(gpu_levels.build_ms);
    extra["pyramid_gpu_filter_ms"] = pb::rounded(gpu_levels.filter_ms);
    extra["max_abs_diff_vs_cpu"] = max_diff;
    extra["mean_abs_diff_vs_cpu"] = field.empty() ? 0.0 : sum_diff / static_cast<double>(field.size());
    // Points beyond float rounding: where the 3/7-cone arrangement's turn about the axis flips
    // (|axis.x| = 0.6, see gpu_occlusion.h) on one path only.
    extra["points_diff_over_1e-4"] = over;
    extra["image_rms_vs_cpu_pct"] =
        pb::rounded(pr::rms_difference_pct(pr::to_rgb8(frame, s.background), pr::to_rgb8(cpu_image, s.background)));
    extra["device"] = device->info().gl_renderer;
    extra["software"] = device->info().software;
    emit(mode, splits, times, frame, reference, extra);
    light_times.clear();
  };
  const pr::ConeTarget towards_eye = pr::ConeTarget::towards_eye(eye);
  for (int splits : {1, 3, 7}) {
    if (modes != "all") break;
    const pr::GpuConeTracer tracer(gpu_pyramid, cone(kAperture, splits, false));
    for (int volume : {0, preillum_res}) {
      std::vector<float> field;
      t = timed([&] {
        field = traced([&] { return tracer.at_mesh_points(towards_eye, s.mesh, volume); });
        return gpu_frame(field);
      }, image);
      emit_gpu(volume ? "ao-object" : "ao-points", splits, t, field, image, with_mc ? &mc_ao_image : nullptr);
    }
  }
  {
    const pr::GpuConeTracer tracer(gpu_pyramid, narrow);
    std::vector<float> field;
    t = timed([&] {
      field = traced([&] {
        // The gap's exact depth on the CPU, as the in-situ path does.
        std::vector<float> cone = tracer.at_mesh_points(pr::ConeTarget::towards_light(sun), s.mesh);
        const std::vector<float> gap = pr::evaluate_at_points(
            mesh, [&](const Vec3d& x) { return pr::gap_transmittance(shadow_cone, sun, x, gap_depth); });
        for (std::size_t p = 0; p < cone.size(); ++p) cone[p] *= gap[p];
        return cone;
      });
      return gpu_frame(field);
    }, image);
    emit_gpu("shadow-cone", 1, t, field, image, with_mc ? &hard_image : nullptr);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return penumbra::bench::guarded_main("pnb_bench_occlusion", run, argc, argv); }

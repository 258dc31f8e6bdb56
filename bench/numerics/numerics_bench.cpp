// SPDX-License-Identifier: BSD-3-Clause
// bench/numerics/numerics_bench.cpp -- the same scene scaled, moved and with its field rescaled
// and offset, on every rendering path, against the untransformed picture, with the frame times.
//
// Usage: pnb_bench_numerics --scene NAME --data-dir DIR [--frames N] [--size WxH]
// Prints one JSON object per (path, transformation): backend, lighting, kind (scale, translate,
// field_offset, field_magnitude), factor, rms_pct and max_level_diff against the untransformed
// picture of the same path, frame_ms (median of N frames) beside the untransformed frame's, and
// the lighting's own time. The field goes through what the in-situ runtime does with a step: the
// values' finite range in double, the map to [0, 1] in double, then float32.
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "bench_util.h"
#include "penumbra/render/occlusion.h"
#include "penumbra/core/error.h"
#include "penumbra/core/field_view.h"
#include "penumbra/render/cpu_ray_caster.h"
#include "penumbra/render/gpu_ray_caster.h"
#include "penumbra/render/image.h"
#include "penumbra/render/light_volume.h"
#include "scene.h"
#include "scene_views.h"

namespace pb = penumbra::bench;
namespace pr = penumbra::render;
using penumbra::Vec3d;

namespace {

/// One transformation of the scene: points, eye, target and lights by x -> scale x + shift (the
/// extinction per world unit divided by the scale), field values by v -> a (v + offset range).
struct Transform {
  std::string kind;
  double factor = 1;
  double scale = 1;
  Vec3d shift{0, 0, 0};
  double field_scale = 1, field_offset = 0;
};

std::vector<Transform> transformations(double diagonal) {
  std::vector<Transform> out;
  for (double s : {1e-15, 1e-12, 1e-9, 1e-6, 1e-3, 1e3, 1e6, 1e9, 1e12, 1e15}) out.push_back({"scale", s, s});
  for (double d : {1e3, 1e5, 1e7}) out.push_back({"translate", d, 1, Vec3d{0.6, -0.7, 0.4} * (d * diagonal)});
  for (double c : {1e3, 1e6, 1e9}) out.push_back({"field_offset", c, 1, {0, 0, 0}, 1, c});
  for (double m : {1e-300, 1e-100, 1e100, 1e300}) out.push_back({"field_magnitude", m, 1, {0, 0, 0}, m, 0});
  return out;
}

/// What one path renders: the prepared mesh, the normalised scalars and transfer function, the
/// camera and the lights.
struct Inputs {
  std::shared_ptr<const pr::TetMesh> mesh;
  std::vector<float> scalars;
  pr::TransferFunction tf;
  pr::Camera camera;
  std::vector<pr::Light> lights;
};

Inputs transformed(const pb::Scene& scene, const Transform& t, int width, int height) {
  pb::Scene s = scene;
  for (std::size_t i = 0; i < s.points.size(); ++i) s.points[i] = s.points[i] * t.scale + t.shift[static_cast<int>(i % 3)];
  Inputs in;
  in.mesh = std::make_shared<const pr::TetMesh>(pr::prepare_tet_mesh(pb::mesh_view(s)));
  pr::Camera cam = pb::camera(scene, width, height);
  cam.eye = cam.eye * t.scale + t.shift;
  cam.target = cam.target * t.scale + t.shift;
  in.camera = cam;
  // The field: v -> a (v + c range), then its finite range and the map to [0, 1] in double; the
  // transfer function's data-unit x follow the same map.
  const penumbra::ValueRange original = penumbra::finite_range(std::vector<double>(scene.scalars.begin(), scene.scalars.end()));
  const double range = original.hi - original.lo;
  std::vector<double> values(scene.scalars.size());
  for (std::size_t i = 0; i < values.size(); ++i) values[i] = t.field_scale * (scene.scalars[i] + t.field_offset * range);
  const penumbra::ValueRange r = penumbra::finite_range(values);
  in.scalars = penumbra::normalize_values(values, r.lo, r.hi);
  in.tf = pb::transfer_function(scene);
  for (auto& c : in.tf.colors) c.x = t.field_scale * (c.x + t.field_offset * range);
  for (auto& o : in.tf.opacities) {
    o.x = t.field_scale * (o.x + t.field_offset * range);
    o.a /= t.scale;
  }
  in.tf.normalize_x(r.lo, r.hi);
  pr::Light key;  // directional
  key.vector = {-0.4, 0.5, -0.8};
  pr::Light lamp;  // a point light beside the mesh
  lamp.kind = pr::Light::Kind::point;
  const penumbra::Bounds& b = in.mesh->bounds;
  lamp.vector = b.hi + (b.hi - b.lo) * 0.3;
  lamp.color = {0.9, 0.6, 0.3};
  in.lights = {key, lamp};
  return in;
}

struct Path {
  std::string backend, lighting;
};

struct Frame {
  pr::Image image;
  double frame_ms = 0, light_ms = 0;
};

/// Lights `in` as `path` says, then renders `frames` frames; the median frame time.
Frame render(const Path& path, const Inputs& in, const std::shared_ptr<pr::GpuDevice>& device, int frames) {
  const bool gpu = path.backend == "gpu";
  pr::RenderOptions options;
  std::unique_ptr<pr::LightVolume> volume;
  std::unique_ptr<penumbra::render::OcclusionLighting> occlusion;
  Frame out;
  pb::Stopwatch light_clock;
  if (path.lighting == "light-volume") {
    pr::LightVolumeOptions o;
    o.level0_resolution = 64;
    o.sigma_s = {0.3, 0.2, 0.1};
    if (gpu) o.device = device;
    volume = std::make_unique<pr::LightVolume>(in.mesh, o);
    volume->set_lights(in.lights);
    volume->set_field(in.scalars, in.tf);
    volume->update();
    options.shading.model = pr::LightingModel::light_volume;
    options.shading.light_rgb = &volume->light_rgb();
  } else if (path.lighting == "occlusion") {
    pr::OcclusionSettings config;
    config.grid_resolution = 64;
    config.volume_resolution = 32;
    occlusion = std::make_unique<pr::OcclusionLighting>(in.mesh, config, in.lights, gpu ? device : nullptr);
    occlusion->set_field(in.scalars, in.tf);
    options.shading.model = pr::LightingModel::light_volume;
    options.shading.light_rgb = &occlusion->light_rgb(in.camera.eye);
  }
  out.light_ms = path.lighting == "none" ? 0 : light_clock.ms();
  std::unique_ptr<pr::CpuRayCaster> cpu;
  std::unique_ptr<pr::GpuRayCaster> caster;
  if (gpu) caster = std::make_unique<pr::GpuRayCaster>(device, in.mesh);
  else cpu = std::make_unique<pr::CpuRayCaster>(in.mesh);
  auto frame = [&] { return gpu ? caster->render(in.scalars, in.tf, in.camera, options) : cpu->render(in.scalars, in.tf, in.camera, options); };
  out.image = frame();  // warm-up
  std::vector<double> times;
  for (int f = 0; f < frames; ++f) {
    pb::Stopwatch clock;
    out.image = frame();
    times.push_back(clock.ms());
  }
  out.frame_ms = pb::median(times);
  return out;
}

int run(int argc, char** argv) {
  const std::string name = pb::option(argc, argv, "scene", "");
  const std::string data_dir = pb::option(argc, argv, "data-dir", "");
  const int frames = std::stoi(pb::option(argc, argv, "frames", "5"));
  const std::string size = pb::option(argc, argv, "size", "256x256");
  penumbra::require(!name.empty() && !data_dir.empty(), "pnb_bench_numerics: --scene NAME and --data-dir DIR are required");
  int width = 0, height = 0;
  penumbra::require(std::sscanf(size.c_str(), "%dx%d", &width, &height) == 2 && width > 0 && height > 0,
                    "pnb_bench_numerics: --size must be WxH");
  const pb::Scene scene = pb::load_scene(name, data_dir);
  const auto device = pb::open_bench_gpu("pnb_bench_numerics");
  std::vector<Path> paths;
  for (const char* lighting : {"none", "light-volume", "occlusion"}) {
    paths.push_back({"cpu", lighting});
    if (device) paths.push_back({"gpu", lighting});
  }
  const Inputs base = transformed(scene, Transform{"none"}, width, height);
  const double diagonal = base.mesh->bounds.diagonal();
  const float background[3] = {scene.background[0], scene.background[1], scene.background[2]};
  for (const Path& path : paths) {
    const Frame reference = render(path, base, device, frames);
    const auto reference_rgb = pr::to_rgb8(reference.image, background);
    for (const Transform& t : transformations(diagonal)) {
      const Frame f = render(path, transformed(scene, t, width, height), device, frames);
      const pb::ImageError e = pb::compare_rgb8(pr::to_rgb8(f.image, background), reference_rgb);
      nlohmann::json line = {{"bench", "numerics"},
                             {"scene", scene.name},
                             {"backend", path.backend},
                             {"lighting", path.lighting},
                             {"kind", t.kind},
                             {"factor", t.factor},
                             {"rms_pct", pb::rounded(e.rms_pct, 4)},
                             {"max_level_diff", e.max_abs},
                             {"frame_ms", pb::rounded(f.frame_ms)},
                             {"frame_ms_untransformed", pb::rounded(reference.frame_ms)},
                             {"frame_ratio", pb::rounded(f.frame_ms / reference.frame_ms)},
                             {"light_ms", pb::rounded(f.light_ms)},
                             {"width", width},
                             {"height", height},
                             {"tets", base.mesh->tet_count()},
                             {"load_average", pb::load_average()}};
      std::cout << line.dump() << std::endl;
    }
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return pb::guarded_main("pnb_bench_numerics", run, argc, argv); }

// SPDX-License-Identifier: BSD-3-Clause
// bench/render/frame_report.cpp -- reference images and shared frame-line keys
#include "frame_report.h"

#include <algorithm>
#include <filesystem>

#include "bench_util.h"
#include "penumbra/core/error.h"
#include "penumbra/render/cpu_ray_caster.h"
#include "penumbra/render/image.h"
#include "scene_views.h"

namespace penumbra::bench {

std::vector<unsigned char> cached_reference(const Scene& scene, const std::string& data_dir, const std::string& who,
                                            const std::string& writer) {
  const std::string path = reference_path(scene, data_dir);
  require(std::filesystem::exists(path), who + ": reference image '" + path + "' is missing (" + writer + " writes it)");
  int w = 0, h = 0;
  std::vector<unsigned char> rgb = render::read_png_rgb(path, w, h);
  require(w == scene.width && h == scene.height, who + ": reference '" + path + "' has the wrong size");
  return rgb;
}

std::vector<unsigned char> reference_image(const Scene& scene, const render::TetMesh& mesh, const std::string& data_dir,
                                           bool refresh, double& render_ms) {
  const std::string path = reference_path(scene, data_dir);
  render_ms = -1;
  if (!refresh && std::filesystem::exists(path)) return cached_reference(scene, data_dir, "reference_image", "reference_image");
  Stopwatch clock;
  std::vector<unsigned char> rgb = render::to_rgb8(
      render::render_reference(mesh, scene.scalars, transfer_function(scene), camera(scene)), scene.background);
  render_ms = clock.ms();
  std::filesystem::create_directories(std::filesystem::path(path).parent_path());
  render::write_png(path, rgb, scene.width, scene.height);
  return rgb;
}

nlohmann::ordered_json frame_line(const std::string& bench, const std::string& renderer, const Scene& scene,
                                  const std::vector<double>& times, const std::vector<unsigned char>& rgb,
                                  const std::vector<unsigned char>& reference, const std::string& image_path) {
  std::filesystem::create_directories(std::filesystem::path(image_path).parent_path());
  render::write_png(image_path, rgb, scene.width, scene.height);
  nlohmann::ordered_json line;
  line["bench"] = bench;
  line["scene"] = scene.name;
  line["scene_kind"] = scene.kind;
  line["renderer"] = renderer;
  line["tets"] = scene.tet_count();
  line["points"] = scene.point_count();
  line["width"] = scene.width;
  line["height"] = scene.height;
  line["frames"] = times.size();
  line["ms_per_frame"] = rounded(median(times));
  line["ms_min"] = rounded(*std::min_element(times.begin(), times.end()));
  if (!reference.empty()) {
    const ImageError err = compare_rgb8(rgb, reference);
    line["rms_error_pct"] = rounded(render::rms_difference_pct(rgb, reference), 4);
    line["max_abs_error"] = err.max_abs;
    line["bad_pixels"] = err.bad_pixels;
  }
  line["image"] = image_path;
  return line;
}

}  // namespace penumbra::bench

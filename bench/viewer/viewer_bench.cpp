// SPDX-License-Identifier: BSD-3-Clause
// bench/viewer/viewer_bench.cpp -- views a run never stored, asked of penumbra-view's server over
// HTTP, from a 64-step store of a ~1M-tet run
//
// Usage: pnb_bench_viewer --scene NAME --data-dir DIR [--steps 64] [--size 512]
//        [--lighting "none light-volume"] [--requests 5]
// For each lighting model, a run through the C API (the scene's field, varying over the steps)
// keeps every step in a store (one window of `steps`, values within 1e-3 of the range) and renders
// steps 0, 21, 42 and 63 in situ from one camera. A ViewServer with that store then answers, in
// this process, over loopback HTTP (the client's time from request to the whole PNG):
//   cold_view_ms       the first view: the store opened, the mesh prepared, the field read
//   new_camera_ms      median of `requests` views of step 42 from new orbit angles (the light,
//                      which does not depend on the camera, reused)
//   new_step_ms        median of new steps (each read through the pager; the light solved
//                      again from the last step's, warm-started)
//   new_tf_ms          median of new transfer functions (opacity scaled; light solved again)
//   rms_vs_insitu_pct, max_level_diff   the view of step 42 from the run's camera against the run's
//                      own image of it (the store's compression and, lit, the light's tolerance)
//   server_*_ms        the server's own split of the new-step requests (load, light, render)
//   store_mb, insitu_s the store's size and the in-situ run's time
// One JSON line per lighting model, bench "viewer".
#include <httplib.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "bench_util.h"
#include "penumbra/core/error.h"
#include "penumbra/penumbra.h"
#include "penumbra/render/image.h"
#include "scene.h"
#include "scene_c_api.h"
#include "view_server.h"

namespace pb = penumbra::bench;
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr int kComparedStep = 42;

void check(pnb_status s, pnb_context ctx, const char* what) {
  if (s != PNB_OK)
    throw penumbra::Error(penumbra::ErrorCode::internal_error,
                          std::string(what) + ": " + (ctx ? pnb_last_error(ctx) : "pnb_create failed"));
}

// The scene's transfer function (data units, extinction per world unit), opacity scaled.
json transfer_function(const pb::Scene& scene, double opacity_scale) {
  json colors = json::array(), opacities = json::array();
  for (const auto& n : scene.tf) {
    colors.push_back({n.x, n.r, n.g, n.b});
    opacities.push_back({n.x, n.extinction * opacity_scale});
  }
  return {{"colors", colors}, {"opacities", opacities}};
}

json run_config(const pb::Scene& scene, const std::string& dir, const std::string& lighting, int steps, int size) {
  json tf = transfer_function(scene, 1);
  tf["x"] = "data";
  tf["opacity_unit"] = "world";
  json c = {{"output", {{"directory", dir + "/db"}}},
            {"image", {{"width", size}, {"height", size}}},
            {"cameras", {{"phi", {30}}, {"theta", {25}}}},
            {"fields", {{{"name", "scalar"}, {"transfer_function", tf}}}},
            {"trigger", {{"every_cycles", 21}}},
            {"store", {{"directory", dir + "/store"}, {"window", steps}, {"error_bound", {{"relative", 1e-3}}}}}};
  if (lighting == "light-volume")
    c["lighting"] = {{"model", "light-volume"}, {"lights", {{{"type", "directional"}, {"direction", {-1, -0.4, -0.8}}}}}};
  return c;
}

// The scene's field at step k: a wave travelling through it, so that every step differs.
std::vector<double> field_at(const pb::Scene& scene, int k, double diagonal) {
  std::vector<double> v(scene.scalars.begin(), scene.scalars.end());
  double lo = v[0], hi = v[0];
  for (double x : v) lo = std::min(lo, x), hi = std::max(hi, x);
  for (std::size_t i = 0; i < v.size(); ++i)
    v[i] += 0.1 * (hi - lo) * std::sin(0.1 * k + 6 * scene.points[3 * i] / diagonal);
  return v;
}

// The run: every step stored, steps 0, 21, 42 and 63 rendered. Returns its seconds.
double run_in_situ(const pb::Scene& scene, const std::string& dir, const std::string& config, int steps) {
  fs::remove_all(dir);
  pb::Stopwatch clock;
  pnb_context ctx = nullptr;
  check(pnb_create(config.c_str(), &ctx), nullptr, "pnb_create");
  pnb_mesh_desc mesh = pb::scene_mesh_desc(scene);
  mesh.points = scene.points.data();
  mesh.topology_version = 1;
  penumbra::Bounds b;
  for (std::size_t i = 0; i < scene.point_count(); ++i)
    b.extend({scene.points[3 * i], scene.points[3 * i + 1], scene.points[3 * i + 2]});
  try {
    check(pnb_publish_mesh(ctx, &mesh, PNB_BORROW), ctx, "pnb_publish_mesh");
    for (int k = 0; k < steps; ++k) {
      const std::vector<double> values = field_at(scene, k, b.diagonal());
      pnb_field_desc field PNB_FIELD_DESC_INIT;
      field.name = "scalar";
      field.values = values.data();
      field.count = static_cast<int64_t>(values.size());
      check(pnb_publish_field(ctx, &field, PNB_BORROW), ctx, "pnb_publish_field");
      check(pnb_execute(ctx, k, k), ctx, "pnb_execute");
    }
    check(pnb_finalize(ctx), ctx, "pnb_finalize");
  } catch (...) {
    pnb_destroy(ctx);
    throw;
  }
  pnb_destroy(ctx);
  return clock.ms() / 1000;
}

std::string percent_encoded(const std::string& text) {
  std::string out;
  for (unsigned char c : text) {
    if (std::isalnum(c) || c == '-' || c == '_' || c == '.') out += static_cast<char>(c);
    else {
      char hex[4];
      std::snprintf(hex, sizeof hex, "%%%02X", c);
      out += hex;
    }
  }
  return out;
}

struct Answer {
  double ms = 0;
  std::string png;
  double load_ms = 0, light_ms = 0, render_ms = 0;
};

Answer ask(httplib::Client& client, const std::string& token, const std::string& query) {
  pb::Stopwatch clock;
  const auto res = client.Get("/api/render?token=" + token + "&" + query);
  Answer a;
  a.ms = clock.ms();
  if (!res || res->status != 200)
    throw penumbra::Error(penumbra::ErrorCode::internal_error,
                          "/api/render?" + query + ": " + (res ? std::to_string(res->status) + " " + res->body : "no answer"));
  a.png = res->body;
  a.load_ms = std::stod(res->get_header_value("X-Penumbra-Load-Ms"));
  a.light_ms = std::stod(res->get_header_value("X-Penumbra-Light-Ms"));
  a.render_ms = std::stod(res->get_header_value("X-Penumbra-Render-Ms"));
  return a;
}

std::vector<unsigned char> decoded(const std::string& png, const std::string& scratch) {
  { std::ofstream(scratch, std::ios::binary) << png; }
  int w = 0, h = 0;
  return penumbra::render::read_png_rgb(scratch, w, h);
}

std::string view_query(int step, double phi, const std::string& tf = "") {
  return "step=" + std::to_string(step) + "&phi=" + std::to_string(phi) + "&theta=25&client=bench" +
         (tf.empty() ? "" : "&tf=" + percent_encoded(tf));
}

nlohmann::ordered_json measure(const pb::Scene& scene, const std::string& data_dir, const std::string& lighting, int steps,
                               int size, int requests) {
  const std::string dir = data_dir + "/viewer-" + lighting;
  const double insitu_s = run_in_situ(scene, dir, run_config(scene, dir, lighting, steps, size).dump(), steps);
  penumbra::viewer::ViewOptions options;
  options.database = dir + "/db";
  options.store = dir + "/store";
  penumbra::viewer::ViewServer server(options);
  std::thread serving([&] { server.run(); });
  nlohmann::ordered_json line;
  try {
    httplib::Client client("127.0.0.1", server.port());
    client.set_read_timeout(600, 0);
    const Answer cold = ask(client, server.token(), view_query(kComparedStep, 30));
    char name[64];
    std::snprintf(name, sizeof name, "/db/scalar/c%06d_phi30_theta25.png", kComparedStep);
    int w = 0, h = 0;
    const pb::ImageError e =
        pb::compare_rgb8(decoded(cold.png, dir + "/view.png"), penumbra::render::read_png_rgb(dir + name, w, h));
    std::vector<double> camera, step, tf, load, light, render;
    for (int i = 1; i <= requests; ++i) camera.push_back(ask(client, server.token(), view_query(kComparedStep, 30 + 7 * i)).ms);
    for (int i = 1; i <= requests; ++i) {
      const Answer a = ask(client, server.token(), view_query(kComparedStep + i, 30));
      step.push_back(a.ms);
      load.push_back(a.load_ms);
      light.push_back(a.light_ms);
      render.push_back(a.render_ms);
    }
    for (int i = 1; i <= requests; ++i)
      tf.push_back(ask(client, server.token(), view_query(kComparedStep + requests, 30, transfer_function(scene, 1 + 0.1 * i).dump())).ms);
    line["bench"] = "viewer";
    line["scene"] = scene.name;
    line["tets"] = scene.tet_count();
    line["steps"] = steps;
    line["lighting"] = lighting;
    line["width"] = size;
    line["cold_view_ms"] = pb::rounded(cold.ms, 1);
    line["new_camera_ms"] = pb::rounded(pb::median(camera), 1);
    line["new_step_ms"] = pb::rounded(pb::median(step), 1);
    line["new_tf_ms"] = pb::rounded(pb::median(tf), 1);
    line["rms_vs_insitu_pct"] = pb::rounded(e.rms_pct, 4);
    line["max_level_diff"] = e.max_abs;
    line["server_load_ms"] = pb::rounded(pb::median(load), 1);
    line["server_light_ms"] = pb::rounded(pb::median(light), 1);
    line["server_render_ms"] = pb::rounded(pb::median(render), 1);
    std::uint64_t bytes = 0;
    for (const auto& f : fs::recursive_directory_iterator(dir + "/store"))
      if (f.is_regular_file()) bytes += f.file_size();
    line["store_mb"] = pb::rounded(bytes / 1e6, 1);
    line["raw_mb"] = pb::rounded(8.0 * scene.point_count() * steps / 1e6, 1);
    line["insitu_s"] = pb::rounded(insitu_s, 1);
    line["requests"] = requests;
    line["load_avg"] = pb::load_average();
  } catch (...) {
    server.stop();
    serving.join();
    throw;
  }
  server.stop();
  serving.join();
  return line;
}

int run(int argc, char** argv) {
  const std::string scene_name = pb::option(argc, argv, "scene", "holeblock-1m");
  const std::string data_dir = pb::option(argc, argv, "data-dir", "build-bench/data");
  const int steps = std::stoi(pb::option(argc, argv, "steps", "64"));
  const int size = std::stoi(pb::option(argc, argv, "size", "512"));
  const int requests = std::stoi(pb::option(argc, argv, "requests", "5"));
  if (steps < 64) throw penumbra::Error(penumbra::ErrorCode::invalid_argument, "--steps must be at least 64");
  const pb::Scene scene = pb::load_scene(scene_name, data_dir);
  std::istringstream models(pb::option(argc, argv, "lighting", "none light-volume"));
  for (std::string lighting; models >> lighting;)
    std::cout << measure(scene, data_dir, lighting, steps, size, requests).dump() << std::endl;
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return pb::guarded_main("pnb_bench_viewer", run, argc, argv); }

// SPDX-License-Identifier: BSD-3-Clause
// bench/moving/moving_bench.cpp -- a mesh whose points move every step, through the C API: the
// geometry update (same topology_version) against a full preparation (a new version each step)
//
// Usage: pnb_bench_moving --scene NAME --data-dir DIR [--frames N] [--size WxH]
//        [--backends "cpu gpu"] [--lighting "none light-volume"] [--store-steps N (0: no store line)]
// Prints one JSON line per backend and lighting, bench "moving":
//   geometry_update_ms   median pnb_publish_mesh of the moved points under the same version
//   full_prepare_ms      median pnb_publish_mesh of the same points as a new topology (the path a
//                        moving mesh took before geometry updates), in the same steps
//   update_ratio         geometry_update_ms / full_prepare_ms
//   rms_pct, max_level_diff  the last step's image (one camera) of the two runs: RMS in % of 255
//                        and the largest channel difference; with the light volume both runs
//                        solve the light to convergence each step
//   step_ms, full_step_ms  median pnb_execute of each run (the light volume's solve included)
// and one line, bench "moving-store", for a Lagrangian series with a store (--store-steps steps,
// windows of 8, fields within 1e-3 of their range, coordinates at the default bound):
//   segments             store segments written (1: the topology never changed)
//   store_ratio          raw bytes (float64 coordinates and field per step) over the bytes the store
//                        keeps of them (its segment less mesh.pnbm, the connectivity kept once,
//                        mesh_mb); coordinates_ratio and field_ratio: each part alone
//   replay_rms_pct       the re-render of two steps from the store against the re-render of the
//                        exact coordinates and field, RMS in % of 255 (and max_level_diff)
// The points move by a swirl about the mesh's vertical axis (a vortex in a Lagrangian code): step
// k rotates a point at distance r from the axis by k * 0.02 * exp(-(r / R)^2), R half the diagonal.
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "bench_util.h"
#include "penumbra/core/error.h"
#include "penumbra/insitu/stored_run.h"
#include "penumbra/penumbra.h"
#include "penumbra/render/image.h"
#include "scene.h"
#include "scene_c_api.h"

namespace pb = penumbra::bench;
namespace fs = std::filesystem;

namespace {

constexpr double kStepAngle = 0.02;

// The scene's points after `step` steps of the swirl.
std::vector<double> swirled(const pb::Scene& scene, int step) {
  penumbra::Bounds b;
  for (std::size_t i = 0; i < scene.point_count(); ++i)
    b.extend({scene.points[3 * i], scene.points[3 * i + 1], scene.points[3 * i + 2]});
  const penumbra::Vec3d c = 0.5 * (b.lo + b.hi);
  const double radius = 0.5 * b.diagonal();
  std::vector<double> out = scene.points;
  for (std::size_t i = 0; i < scene.point_count(); ++i) {
    const double x = out[3 * i] - c.x, y = out[3 * i + 1] - c.y;
    const double a = step * kStepAngle * std::exp(-(x * x + y * y) / (radius * radius));
    out[3 * i] = c.x + std::cos(a) * x - std::sin(a) * y;
    out[3 * i + 1] = c.y + std::sin(a) * x + std::cos(a) * y;
  }
  return out;
}

void check(pnb_status s, pnb_context ctx, const char* what) {
  if (s != PNB_OK)
    throw penumbra::Error(penumbra::ErrorCode::internal_error,
                          std::string(what) + ": " + (ctx ? pnb_last_error(ctx) : "pnb_create failed"));
}

std::string config(const std::string& dir, const std::string& backend, const std::string& lighting, int w, int h) {
  std::string c = R"({"output": {"directory": ")" + dir + R"("}, "backend": ")" + backend + R"(",
      "image": {"width": )" + std::to_string(w) + R"(, "height": )" + std::to_string(h) + R"(},
      "cameras": {"phi": [30], "theta": [25]}, "fields": [{"name": "scalar"}])";
  if (lighting == "light-volume")
    c += R"(, "lighting": {"model": "light-volume", "absorption": 1,
        "lights": [{"type": "directional", "direction": [-1, -0.4, -0.8]}]})";
  return c + "}";
}

// One run of the scene: its context and the mesh and field descriptions it publishes.
struct Run {
  pnb_context ctx = nullptr;
  std::string dir;
  pnb_mesh_desc mesh = PNB_MESH_DESC_INIT;
  pnb_field_desc field = PNB_FIELD_DESC_INIT;
  std::vector<double> publish_ms, execute_ms;

  Run(const pb::Scene& scene, const std::vector<double>& values, const std::string& d, const std::string& cfg) : dir(d) {
    fs::remove_all(dir);
    check(pnb_create(cfg.c_str(), &ctx), nullptr, "pnb_create");
    mesh = pb::scene_mesh_desc(scene);
    field.name = "scalar";
    field.values = values.data();
    field.count = static_cast<int64_t>(values.size());
  }
  ~Run() { pnb_destroy(ctx); }
  void publish(const std::vector<double>& points, std::uint64_t version) {
    mesh.points = points.data();
    mesh.topology_version = version;
    pb::Stopwatch clock;
    check(pnb_publish_mesh(ctx, &mesh, PNB_BORROW), ctx, "pnb_publish_mesh");
    publish_ms.push_back(clock.ms());
  }
  void execute(int step) {
    check(pnb_publish_field(ctx, &field, PNB_BORROW), ctx, "pnb_publish_field");
    pb::Stopwatch clock;
    check(pnb_execute(ctx, step, step), ctx, "pnb_execute");
    execute_ms.push_back(clock.ms());
  }
  std::vector<unsigned char> last_image(int step) const {
    int w = 0, h = 0;
    char name[64];
    std::snprintf(name, sizeof name, "scalar/c%06d_phi30_theta25.png", step);
    return penumbra::render::read_png_rgb(dir + "/" + name, w, h);
  }
};

nlohmann::ordered_json measure(const pb::Scene& scene, const std::string& data_dir, const std::string& backend,
                               const std::string& lighting, int steps, int w, int h) {
  const std::vector<double> values(scene.scalars.begin(), scene.scalars.end());
  const std::string base = data_dir + "/moving-" + backend + "-" + lighting;
  Run moving(scene, values, base + "-update", config(base + "-update", backend, lighting, w, h));
  Run full(scene, values, base + "-full", config(base + "-full", backend, lighting, w, h));
  const bool lit = lighting != "none";
  std::vector<std::vector<double>> points;
  for (int k = 0; k <= steps; ++k) points.push_back(swirled(scene, k));
  for (int k = 0; k <= steps; ++k) {
    // The two runs take turns going first, so that neither always finds the caches warm.
    Run* order[2] = {&moving, &full};
    if (k % 2) std::swap(order[0], order[1]);
    for (Run* r : order) r->publish(points[static_cast<std::size_t>(k)], r == &full ? static_cast<std::uint64_t>(k + 1) : 1);
    // Unlit, only the last step renders; lit, every step does, so that the light volume moves.
    if (lit || k == steps)
      for (Run* r : order) r->execute(k);
  }
  // The first publish of each run is a preparation in both; the steps after it are compared.
  const std::vector<double> update(moving.publish_ms.begin() + 1, moving.publish_ms.end());
  const std::vector<double> prepare(full.publish_ms.begin() + 1, full.publish_ms.end());
  const pb::ImageError e = pb::compare_rgb8(moving.last_image(steps), full.last_image(steps));
  nlohmann::ordered_json line;
  line["bench"] = "moving";
  line["scene"] = scene.name;
  line["backend"] = backend;
  line["lighting"] = lighting;
  line["tets"] = scene.tet_count();
  line["points"] = scene.point_count();
  line["steps"] = steps;
  line["geometry_update_ms"] = pb::rounded(pb::median(update), 1);
  line["full_prepare_ms"] = pb::rounded(pb::median(prepare), 1);
  line["update_ratio"] = pb::rounded(pb::median(update) / pb::median(prepare), 3);
  line["rms_pct"] = pb::rounded(e.rms_pct, 4);
  line["max_level_diff"] = e.max_abs;
  line["step_ms"] = pb::rounded(pb::median(moving.execute_ms), 1);
  line["full_step_ms"] = pb::rounded(pb::median(full.execute_ms), 1);
  line["width"] = w;
  line["height"] = h;
  line["load_avg"] = pb::load_average();
  return line;
}

std::uint64_t bytes_under(const std::string& dir) {
  std::uint64_t n = 0;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    if (e.is_regular_file()) n += e.file_size();
  return n;
}

// The field of the Lagrangian series at step k: the scene's, warming a little every step.
std::vector<double> series_field(const pb::Scene& scene, int k) {
  std::vector<double> v(scene.scalars.begin(), scene.scalars.end());
  for (double& x : v) x *= 1.0 + 0.02 * k;
  return v;
}

nlohmann::ordered_json measure_store(const pb::Scene& scene, const std::string& data_dir, int steps, int w, int h) {
  const std::string dir = data_dir + "/moving-store", history = dir + "/history";
  fs::remove_all(dir);
  const std::string store = R"(, "trigger": {"every_cycles": 1000000000}, "store": {"directory": ")" + history +
                            R"(", "window": 8, "error_bound": {"relative": 0.001}}})";
  std::string with_store = config(dir + "/db", "cpu", "none", w, h);
  with_store.pop_back();
  pb::Stopwatch clock;
  {
    std::vector<double> values = series_field(scene, 0);
    Run solver(scene, values, dir + "/db", with_store + store);
    for (int k = 0; k < steps; ++k) {
      values = series_field(scene, k);
      solver.field.values = values.data();
      solver.publish(swirled(scene, k), 1);
      solver.execute(k);
    }
    check(pnb_finalize(solver.ctx), solver.ctx, "pnb_finalize");
  }
  const double run_ms = clock.ms();
  int segments = 0;
  for (const auto& e : fs::directory_iterator(history)) segments += e.path().filename().string().rfind("segment-", 0) == 0;
  const double raw = static_cast<double>(steps) * static_cast<double>(scene.point_count()) * 4 * sizeof(double);

  // Two steps re-rendered from the store and from the exact data, with the same config.
  auto stored = penumbra::insitu::StoredRun::open(history + "/segment-000");
  pb::ImageError worst;
  for (const int k : {steps / 2, steps - 1}) {
    std::vector<double> xyz, values;
    stored->read_points(static_cast<std::size_t>(k), xyz);
    stored->read("scalar", static_cast<std::size_t>(k), values);
    const std::vector<double> exact_values = series_field(scene, k);
    Run from_store(scene, values, dir + "/from-store", config(dir + "/from-store", "cpu", "none", w, h));
    Run from_exact(scene, exact_values, dir + "/exact", config(dir + "/exact", "cpu", "none", w, h));
    from_store.publish(xyz, 1);
    from_exact.publish(swirled(scene, k), 1);
    from_store.execute(k);
    from_exact.execute(k);
    const pb::ImageError e = pb::compare_rgb8(from_store.last_image(k), from_exact.last_image(k));
    if (e.rms_pct >= worst.rms_pct) worst = e;
  }
  nlohmann::ordered_json line;
  line["bench"] = "moving-store";
  line["scene"] = scene.name;
  line["tets"] = scene.tet_count();
  line["points"] = scene.point_count();
  line["steps"] = steps;
  line["segments"] = segments;
  const std::string segment = history + "/segment-000";
  const double coordinates = static_cast<double>(bytes_under(segment + "/coordinates"));
  const double series = static_cast<double>(bytes_under(segment)) - static_cast<double>(fs::file_size(segment + "/mesh.pnbm"));
  line["store_ratio"] = pb::rounded(raw / series, 2);
  line["coordinates_ratio"] = pb::rounded(0.75 * raw / coordinates, 2);
  line["field_ratio"] = pb::rounded(0.25 * raw / (series - coordinates), 2);
  line["series_mb"] = pb::rounded(series / (1 << 20), 2);
  line["mesh_mb"] = pb::rounded(static_cast<double>(fs::file_size(segment + "/mesh.pnbm")) / (1 << 20), 2);
  line["replay_rms_pct"] = pb::rounded(worst.rms_pct, 4);
  line["max_level_diff"] = worst.max_abs;
  line["run_ms_per_step"] = pb::rounded(run_ms / steps, 1);
  line["load_avg"] = pb::load_average();
  return line;
}

int run(int argc, char** argv) {
  const std::string name = pb::option(argc, argv, "scene", "holeblock-1m");
  const std::string data_dir = pb::option(argc, argv, "data-dir", "");
  const int steps = std::stoi(pb::option(argc, argv, "frames", "5"));
  const std::string size = pb::option(argc, argv, "size", "256x256");
  std::istringstream backends(pb::option(argc, argv, "backends", "cpu gpu"));
  const std::string lightings = pb::option(argc, argv, "lighting", "none light-volume");
  const int store_steps = std::stoi(pb::option(argc, argv, "store-steps", "16"));
  penumbra::require(!data_dir.empty(), "pnb_bench_moving: --data-dir DIR is required");
  penumbra::require(steps >= 2, "pnb_bench_moving: --frames must be >= 2");
  int w = 0, h = 0;
  penumbra::require(std::sscanf(size.c_str(), "%dx%d", &w, &h) == 2 && w > 0 && h > 0,
                    "pnb_bench_moving: --size '" + size + "', expected WxH");
  const pb::Scene scene = pb::load_scene(name, data_dir);
  for (std::string backend; backends >> backend;) {
    if (backend == "gpu" && !pb::open_bench_gpu("pnb_bench_moving")) continue;
    std::istringstream each(lightings);
    for (std::string lighting; each >> lighting;)
      std::cout << measure(scene, data_dir, backend, lighting, steps, w, h).dump() << std::endl;
  }
  if (store_steps > 0) std::cout << measure_store(scene, data_dir, store_steps, w, h).dump() << std::endl;
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return pb::guarded_main("pnb_bench_moving", run, argc, argv); }

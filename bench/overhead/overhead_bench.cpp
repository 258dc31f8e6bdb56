// SPDX-License-Identifier: BSD-3-Clause
// bench/overhead/overhead_bench.cpp -- what Penumbra costs a solver: a stand-in solver's run with
// and without it, synchronous and asynchronous
//
// Usage: pnb_bench_overhead --scene NAME --data-dir DIR [--steps 40] [--every 10] [--runs 3]
//        [--size 256] [--modes "sync async"] [--lighting "none light-volume occlusion"]
//        [--stores "off on"] [--moving "off on"] [--sweeps 30] [--limits "budget max_share"]
// The solver: `sweeps` sweeps of a diffusion of its field over the mesh's tets per step (a gather
// and a scatter per tet, the memory-bound work of an unstructured solver's step: about 0.3 ms per
// sweep per 100K tets here), and with --moving on a swirl of its points too, republished every
// step. It publishes the field every step, asks pnb_step_needs first and
// builds nothing when the step needs nothing; Penumbra renders one camera every `every` steps
// (and with a store records every step). Runs alternate: solver alone, solver with Penumbra, for
// `runs` pairs; medians. One JSON line per configuration, bench "overhead":
//   mode, lighting, store, moving, tets, steps, every
//   solver_ms_per_step   the solver alone
//   overhead_pct         (with Penumbra - alone) / alone over the whole run, pnb_finalize included
//   execute_visible_ms   median time a rendering step's pnb_execute kept the solver (async: the
//                        decision and the copy of the fields; sync: the whole step)
//   publish_visible_ms   median time a rendering step's pnb_publish_mesh and pnb_publish_field
//                        kept the solver (with a moving mesh, the copy of its points)
//   execute_ms_per_image_per_mtet  sync: that step per image per million tets
//   published_bytes, memcpy_ms     the bytes the step reads, and one memcpy of them, same run
//   skipped_steps        the async worker's skipped steps ("wait" back-pressure: 0 expected)
//   solver_slowdown_pct  how much longer the solver's own steps took beside Penumbra than alone
//                        (async: what the worker's competition for cores and memory costs it)
// With --limits, two more synchronous light-volume lines per scene, over four times the steps (a
// budget's first steps measure and coarsen level 0 once): "budget": {"share": 1} (a rendering
// step may take one solver step's time: budget_share, degraded_steps, over_budget_steps, what
// the last one gave up, and execute_visible_ms over the steps after the first two) and
// "trigger": {"max_share": 0.2} (the adaptive cadence: max_share, and rendered_steps of the
// steps the cycle rule renders).
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "bench_util.h"
#include "penumbra/core/error.h"
#include "penumbra/penumbra.h"
#include "scene.h"
#include "scene_c_api.h"

namespace pb = penumbra::bench;
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

struct Setup {
  std::string mode, lighting, store, moving;
  int steps = 40, every = 10, size = 256, sweeps = 30;
  double budget_share = 0;  ///< "budget": {"share"}; 0 = none
  double max_share = 0;     ///< "trigger": {"max_share"}; 0 = none
};

void check(pnb_status s, pnb_context ctx, const char* what) {
  if (s != PNB_OK)
    throw penumbra::Error(penumbra::ErrorCode::internal_error,
                          std::string(what) + ": " + (ctx ? pnb_last_error(ctx) : pnb_last_error(nullptr)));
}

std::string config(const pb::Scene& scene, const std::string& dir, const Setup& s) {
  json tf = {{"x", "data"}, {"opacity_unit", "world"}, {"colors", json::array()}, {"opacities", json::array()}};
  for (const auto& n : scene.tf) {
    tf["colors"].push_back({n.x, n.r, n.g, n.b});
    tf["opacities"].push_back({n.x, n.extinction});
  }
  json c = {{"output", {{"directory", dir + "/db"}}},
            {"image", {{"width", s.size}, {"height", s.size}}},
            {"cameras", {{"phi", {30}}, {"theta", {25}}}},
            {"fields", {{{"name", "u"}, {"transfer_function", tf}}}},
            {"trigger", {{"every_cycles", s.every}}},
            {"progress", {{"log", dir + "/progress.jsonl"}}}};
  if (s.max_share > 0) c["trigger"]["max_share"] = s.max_share;
  if (s.budget_share > 0) c["budget"] = {{"share", s.budget_share}};
  const json light = {{"type", "directional"}, {"direction", {-1, -0.4, -0.8}}};
  if (s.lighting == "light-volume") c["lighting"] = {{"model", "light-volume"}, {"lights", {light}}};
  if (s.lighting == "occlusion") c["lighting"] = {{"model", "occlusion"}, {"lights", {light}}};
  if (s.store == "on") c["store"] = {{"directory", dir + "/store"}, {"window", 8}, {"error_bound", {{"relative", 1e-3}}}};
  if (s.mode == "async") c["async"] = {{"backpressure", "wait"}};
  return c.dump();
}

/// The stand-in solver: explicit diffusion along the tets' edges, and optionally a swirl.
struct Solver {
  const pb::Scene& scene;
  std::vector<double> u, next, points;
  double cx = 0, cy = 0, radius = 1;
  explicit Solver(const pb::Scene& s) : scene(s), u(s.scalars.begin(), s.scalars.end()), next(u.size()), points(s.points) {
    penumbra::Bounds b;
    for (std::size_t i = 0; i < s.point_count(); ++i) b.extend({s.points[3 * i], s.points[3 * i + 1], s.points[3 * i + 2]});
    cx = 0.5 * (b.lo.x + b.hi.x), cy = 0.5 * (b.lo.y + b.hi.y), radius = 0.5 * b.diagonal();
  }
  void step(bool moving, int sweeps) {
    for (int sweep = 0; sweep < sweeps; ++sweep) {
      next = u;
      for (std::size_t t = 0; t < scene.tet_count(); ++t) {
        const std::int64_t* v = &scene.tets[4 * t];
        const double mean = 0.25 * (u[v[0]] + u[v[1]] + u[v[2]] + u[v[3]]);
        for (int k = 0; k < 4; ++k) next[v[k]] += 0.001 * (mean - u[v[k]]);
      }
      u.swap(next);
    }
    if (!moving) return;
    for (std::size_t i = 0; i < scene.point_count(); ++i) {
      const double x = points[3 * i] - cx, y = points[3 * i + 1] - cy;
      const double a = 0.002 * std::exp(-(x * x + y * y) / (radius * radius));
      points[3 * i] = cx + std::cos(a) * x - std::sin(a) * y;
      points[3 * i + 1] = cy + std::sin(a) * x + std::cos(a) * y;
    }
  }
};

struct RunResult {
  double total_ms = 0;
  double solver_ms = 0;  ///< in the solver's own steps
  std::vector<double> visible_ms, publish_ms;
  std::int64_t skipped = 0;
  int rendered = 0, degraded = 0, over_budget = 0;
  std::string last_degradation;
};

/// What a synchronous step gave up, in the database's words.
std::string degradation_text(const pnb_step_stats& s) {
  std::string t;
  const auto add = [&t](const std::string& part) { t += (t.empty() ? "" : "+") + part; };
  if (s.degraded & PNB_DEGRADED_LIGHT) add("light");
  if (s.degraded & PNB_DEGRADED_LEVEL0) add("level0:" + std::to_string(s.level0_resolution));
  if (s.degraded & PNB_DEGRADED_IMAGE) add("image:" + std::to_string(s.image_scale).substr(0, 6));
  if (s.degraded & PNB_DEGRADED_CAMERAS) add("cameras:" + std::to_string(s.cameras_rendered));
  return t.empty() ? "none" : t;
}

RunResult run(const pb::Scene& scene, const std::string& dir, const Setup& s, bool with_penumbra) {
  Solver solver(scene);
  RunResult r;
  pnb_context ctx = nullptr;
  fs::remove_all(dir);
  fs::create_directories(dir);
  pb::Stopwatch clock;
  if (with_penumbra) check(pnb_create(config(scene, dir, s).c_str(), &ctx), nullptr, "pnb_create");
  pnb_mesh_desc mesh = pb::scene_mesh_desc(scene);
  mesh.points = solver.points.data();
  mesh.topology_version = 1;
  for (int k = 0; k < s.steps; ++k) {
    pb::Stopwatch solving;
    solver.step(s.moving == "on", s.sweeps);
    r.solver_ms += solving.ms();
    if (!ctx) continue;
    pnb_needs needs = PNB_NEEDS_INIT;
    check(pnb_step_needs(ctx, k, k, &needs), ctx, "pnb_step_needs");
    pb::Stopwatch publishing;
    if (needs.needs_mesh || s.moving == "on") check(pnb_publish_mesh(ctx, &mesh, PNB_BORROW), ctx, "pnb_publish_mesh");
    if (needs.field_count > 0) {
      pnb_field_desc f = PNB_FIELD_DESC_INIT;
      f.name = "u";
      f.values = solver.u.data();
      f.count = static_cast<int64_t>(solver.u.size());
      check(pnb_publish_field(ctx, &f, PNB_BORROW), ctx, "pnb_publish_field");
    }
    const double publish_ms = publishing.ms();
    pb::Stopwatch visible;
    check(pnb_execute(ctx, k, k), ctx, "pnb_execute");
    if (!needs.renders) continue;
    r.visible_ms.push_back(visible.ms());
    r.publish_ms.push_back(publish_ms);
    if (s.mode != "sync") continue;
    pnb_step_stats stats = PNB_STEP_STATS_INIT;
    pnb_last_step(ctx, &stats);
    if (stats.cycle != k) continue;  // left out by the adaptive cadence
    ++r.rendered;
    if (stats.degraded) ++r.degraded, r.last_degradation = degradation_text(stats);
    if (stats.budget_ms > 0 && stats.total_ms > stats.budget_ms) ++r.over_budget;
  }
  if (ctx) {
    check(pnb_finalize(ctx), ctx, "pnb_finalize");
    pnb_step_stats stats = PNB_STEP_STATS_INIT;
    pnb_last_step(ctx, &stats);
    r.skipped = stats.skipped_steps;
    pnb_destroy(ctx);
  }
  r.total_ms = clock.ms();
  return r;
}

double memcpy_ms(std::size_t bytes) {
  std::vector<char> a(bytes, 1), b(bytes);
  std::vector<double> t;
  for (int i = 0; i < 5; ++i) {
    pb::Stopwatch clock;
    std::memcpy(b.data(), a.data(), bytes);
    t.push_back(clock.ms());
  }
  return pb::median(t);
}

json measure(const pb::Scene& scene, const std::string& data_dir, const Setup& s, int runs) {
  std::vector<double> alone, with, visible, publishing, solving_alone, solving_with;
  std::int64_t skipped = 0;
  RunResult last;
  const std::string dir = data_dir + "/overhead";
  for (int i = 0; i < runs; ++i) {
    // Alternated, so that neither side always runs on a warmer or quieter machine.
    const RunResult a = run(scene, dir, s, false);
    alone.push_back(a.total_ms);
    solving_alone.push_back(a.solver_ms);
    const RunResult r = run(scene, dir, s, true);
    with.push_back(r.total_ms);
    solving_with.push_back(r.solver_ms);
    // A budget's first two rendering steps measure, then coarsen level 0 once: set-up, not steady.
    const std::size_t skip = s.budget_share > 0 && r.visible_ms.size() > 2 ? 2 : 0;
    visible.insert(visible.end(), r.visible_ms.begin() + static_cast<std::ptrdiff_t>(skip), r.visible_ms.end());
    publishing.insert(publishing.end(), r.publish_ms.begin(), r.publish_ms.end());
    skipped += r.skipped;
    last = r;
  }
  const double a = pb::median(alone), w = pb::median(with);
  const std::size_t bytes = 8 * scene.point_count() * (s.moving == "on" ? 4 : 1);
  nlohmann::ordered_json line;
  line["bench"] = "overhead";
  line["scene"] = scene.name;
  line["mode"] = s.mode;
  line["lighting"] = s.lighting;
  line["store"] = s.store;
  line["moving"] = s.moving;
  line["tets"] = scene.tet_count();
  line["steps"] = s.steps;
  line["every"] = s.every;
  line["sweeps"] = s.sweeps;
  line["solver_ms_per_step"] = pb::rounded(a / s.steps, 2);
  line["overhead_pct"] = pb::rounded(100 * (w - a) / a, 1);
  line["execute_visible_ms"] = pb::rounded(pb::median(visible), 2);
  line["publish_visible_ms"] = pb::rounded(pb::median(publishing), 2);
  if (s.mode == "sync")
    line["execute_ms_per_image_per_mtet"] = pb::rounded(pb::median(visible) / (scene.tet_count() / 1e6), 1);
  line["published_bytes"] = bytes;
  line["memcpy_ms"] = pb::rounded(memcpy_ms(bytes), 3);
  line["skipped_steps"] = skipped;
  line["solver_slowdown_pct"] = pb::rounded(100 * (pb::median(solving_with) / pb::median(solving_alone) - 1), 1);
  if (s.budget_share > 0) {
    line["budget_share"] = s.budget_share;
    line["degraded_steps"] = last.degraded;
    line["over_budget_steps"] = last.over_budget;
    line["rendering_steps"] = last.rendered;
    line["last_degradation"] = last.last_degradation.empty() ? "none" : last.last_degradation;
  }
  if (s.max_share > 0) {
    line["max_share"] = s.max_share;
    line["rendered_steps"] = last.rendered;
    line["cycle_rule_steps"] = (s.steps + s.every - 1) / s.every;
  }
  line["runs"] = runs;
  line["width"] = s.size;
  line["load_avg"] = pb::load_average();
  return line;
}

std::vector<std::string> words(const std::string& text) {
  std::istringstream in(text);
  std::vector<std::string> out;
  for (std::string w; in >> w;) out.push_back(w);
  return out;
}

int run_all(int argc, char** argv) {
  const pb::Scene scene = pb::load_scene(pb::option(argc, argv, "scene", "holeblock-100k"), pb::option(argc, argv, "data-dir", "build-bench/data"));
  const std::string data_dir = pb::option(argc, argv, "data-dir", "build-bench/data");
  Setup base;
  base.steps = std::stoi(pb::option(argc, argv, "steps", "40"));
  base.every = std::stoi(pb::option(argc, argv, "every", "10"));
  base.size = std::stoi(pb::option(argc, argv, "size", "256"));
  base.sweeps = std::stoi(pb::option(argc, argv, "sweeps", "30"));
  const int runs = std::stoi(pb::option(argc, argv, "runs", "3"));
  for (const std::string& moving : words(pb::option(argc, argv, "moving", "off on")))
    for (const std::string& lighting : words(pb::option(argc, argv, "lighting", "none light-volume occlusion")))
      for (const std::string& store : words(pb::option(argc, argv, "stores", "off on")))
        for (const std::string& mode : words(pb::option(argc, argv, "modes", "sync async"))) {
          // The moving solver is measured unlit without a store: its cost is the republished mesh.
          if (moving == "on" && (lighting != "none" || store != "off")) continue;
          Setup s = base;
          s.mode = mode, s.lighting = lighting, s.store = store, s.moving = moving;
          std::cout << measure(scene, data_dir, s, runs).dump() << std::endl;
        }
  for (const std::string& limit : words(pb::option(argc, argv, "limits", "budget max_share"))) {
    Setup s = base;
    s.mode = "sync", s.lighting = "light-volume", s.store = "off", s.moving = "off";
    s.steps = 4 * base.steps;
    if (limit == "budget") s.budget_share = 1;
    if (limit == "max_share") s.max_share = 0.2;
    std::cout << measure(scene, data_dir, s, runs).dump() << std::endl;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return pb::guarded_main("pnb_bench_overhead", run_all, argc, argv); }

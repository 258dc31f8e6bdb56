// SPDX-License-Identifier: BSD-3-Clause
// render/src/lighting/light_volume.cpp -- Algorithm 1: incremental two-level light volume updates
#include "penumbra/render/light_volume.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <string>

#include "gpu_light_solver.h"
#include "level0_grid.h"
#include "level0_sweep.h"
#include "tet_order.h"
#include "level1_mesh.h"
#include "level1_solve.h"
#include "light_scattering.h"
#include "penumbra/core/elapsed.h"
#include "penumbra/core/error.h"
#include "penumbra/core/thread_pool.h"

namespace penumbra::render {
namespace {

using Clock = std::chrono::steady_clock;
// A recorded level-1 walk (PassState::walks) per point: the 56-byte record and about
// kCrossingsPerWalk crossings of 28 B in the light's arena.
constexpr std::size_t kCrossingsPerWalk = 8;
constexpr double kWalkBytesPerPoint = 320.0;
// Points per task when a frame's share of the points is combined or copied out in parallel
// (about 25 000 per level-1 frame at 1M tets: 0.6 ms of a 13 ms budget on one thread).
constexpr std::size_t kPointsPerTask = 4096;
// The smallest scattering tolerance (relative to max |L|) that float iterates can meet: 16 ulp.
constexpr double kScatterToleranceFloor = 16.0 / (1 << 24);

void check_options(const LightVolumeOptions& o) {
  const std::string call = "LightVolume: ";
  require(o.level0_resolution >= 2,
          call + "level0_resolution = " + std::to_string(o.level0_resolution) + "; expected >= 2");
  require(std::isfinite(o.sigma_a) && o.sigma_a >= 0, call + "sigma_a = " + std::to_string(o.sigma_a) +
                                                          "; expected a finite value >= 0");
  for (double s : o.sigma_s)
    require(std::isfinite(s) && s >= 0, call + "sigma_s has " + std::to_string(s) + "; expected finite values >= 0");
  require(o.propagation_tolerance > 0 && o.scatter_tolerance > 0, call + "tolerances must be > 0");
  require(std::isfinite(o.level1_step) && o.level1_step >= 0,
          call + "level1_step = " + std::to_string(o.level1_step) + "; expected >= 0 (0 = automatic)");
  require(o.level1_max_passes >= 1 && o.scatter_max_iterations >= 1, call + "iteration caps must be >= 1");
  for (std::size_t i = 0; i < o.occluders.size(); ++i) {
    const Bounds& b = o.occluders[i];
    bool ok = !b.empty();
    for (int a = 0; a < 3; ++a) ok = ok && std::isfinite(b.lo[a]) && std::isfinite(b.hi[a]) && b.lo[a] <= b.hi[a];
    require(ok, call + "occluders[" + std::to_string(i) + "] is empty or not finite; expected lo <= hi");
  }
}

void check_light(const Light& l, std::size_t i) {
  const std::string at = "LightVolume::set_lights: lights[" + std::to_string(i) + "]";
  bool finite = true;
  for (int a = 0; a < 3; ++a) finite = finite && std::isfinite(l.vector[a]);
  require(finite, at + " has a non-finite vector; expected finite coordinates");
  if (l.kind == Light::Kind::directional)
    require(length(l.vector) > 0, at + " is directional with a zero direction; expected a non-zero vector");
  for (double c : l.color)
    require(std::isfinite(c) && c >= 0, at + " has colour channel " + std::to_string(c) + "; expected finite >= 0");
}

}  // namespace

struct LightVolume::Impl {
  struct LightState {
    Light light;
    enum class Stage { level0, level1, done } stage = Stage::level0;
    std::vector<float> rho0;         // per level-0 node
    std::vector<float> rho0_vertex;  // level 0 at the mesh points (initial values; warm-start reference)
    std::vector<float> rho1;         // per mesh point (the solver's order, see point_order)
    // rho1 in the caller's point order, copied when light_rho asks for it (nothing renders from
    // it, so the frame budget does not pay for it).
    mutable std::vector<float> rho1_out;
    mutable bool rho1_out_stale = true;
    lighting::VertexOrder order;
    lighting::PassState pass_state;
    bool order_valid = false;
    bool has_solution = false;
    int passes = 0;
    double residual = HUGE_VAL;
    bool converged = false;  // false when the pass cap stopped it
    // GPU solve: the light's device buffers; its level-1 values there are stale after a CPU
    // change (initial values, warm start).
    std::shared_ptr<lighting::GpuLightBuffers> gpu;
    bool gpu_rho1_stale = true;
    // The light moved (or the step changed): its vertex order and walks are stale, and each
    // vertex's start tet becomes a hint for the next walk.
    void forget_direction() {
      order_valid = false;
      for (std::int32_t& start : pass_state.start_tet) start = lighting::hint_start(start);
      pass_state.forget_walks();
    }
  };

  // The caller's mesh with its points renumbered along a Morton curve: the walks, the scattering
  // and every per-point array run in that order, where the points of nearby tets sit nearby in
  // memory (in the input's order a walk step missed the cache on most points; 14 % faster at 1M
  // tets). Point i here is the caller's point point_order[i]; results are copied back to the
  // caller's order after every update.
  std::shared_ptr<const TetMesh> mesh;
  std::vector<std::int32_t> point_order;
  std::vector<float> rgb_out;  // rgb in the caller's point order (light_rgb)
  LightVolumeOptions opt;
  lighting::Level1Topology topology;
  std::vector<float> scatter_weights;
  lighting::ScatterPlan scatter_plan;
  // The CPU sweeps' source and iterate in the plan's order (light_scattering.h), copied in when
  // the source changes and back to rgb after each frame's sweeps.
  std::vector<float> pre_planned, rgb_planned;
  bool cpu_scatter_stale = true;
  lighting::Level0Grid grid;
  lighting::Level1Field field;
  std::vector<float> scalars;
  std::unique_ptr<lighting::GpuLightSolver> gpu;  // null: the CPU solves
  bool gpu_scatter_stale = true;                  // the device's scattering source is out of date
  bool has_field = false, resample_pending = false;
  std::vector<LightState> lights;
  std::vector<float> pre, rgb, previous_pre;
  double pre_scale = 0;
  bool pre_scale_stale = false;
  // combine_pending: every point is combined and copied out; else only combine_points (the
  // points whose level-1 value changed since), and copied out are only those of the last
  // combine (published_points) unless the scattering ran (publish_all).
  bool combine_pending = true, scatter_done = false, publish_all = true;
  std::vector<std::int32_t> combine_points, published_points;
  std::vector<std::uint8_t> listed;  // per point: in combine_points (each point is listed once)
  int scatter_iterations = 0;
  double scatter_residual = HUGE_VAL;
  bool scatter_converged = false;
  bool has_rgb = false;
  std::vector<float> scratch0;
  std::vector<float> at_vertex_scratch;  // a level-0 solve's values at the vertices, before they become the light's
  // The working memory of the first light set, allocated with the volume (prime_first_light).
  LightState first_light;
  bool first_light_ready = false;
  double step = 0;
  // The last durations, for the time budget's look-ahead (-1: not timed yet).
  double last_level0_ms = -1, last_sweep_ms = -1, last_order_ms = -1;
  lighting::ScatterSolve solve;  // the CPU iteration in progress (a frame may end inside one)
  double last_chunk_ms = -1;     // one block of a CPU iteration
  // Combining the lights follows every level-1 call, and copying the results to the caller's
  // order ends every call: both are kept out of the budget, each by the last duration of its
  // kind (all points, or those a level-1 piece changed; a volume's first calls combine all).
  double last_full_combine_ms = 0, last_partial_combine_ms = 0;
  double last_full_publish_ms = 0, last_partial_publish_ms = 0, last_copy_back_ms = 0, last_scatter_setup_ms = -1;
  // Whether the next combine and publish take every point (combine() and publish() decide by
  // these; a full combine makes the publish after it full).
  bool combine_is_full() const {
    const std::size_t n = 3 * mesh->points.size();
    return combine_pending || !has_rgb || pre.size() != n || rgb.size() != n;
  }
  bool publish_takes_all() const { return publish_all || rgb_out.size() != 3 * mesh->points.size(); }
  bool publish_is_full() const { return combine_is_full() || publish_takes_all(); }
  bool scatters() const { return opt.sigma_s[0] > 0 || opt.sigma_s[1] > 0 || opt.sigma_s[2] > 0; }
  double expected_publish_ms() const { return publish_is_full() ? last_full_publish_ms : last_partial_publish_ms; }
  double expected_combine_ms() const { return combine_is_full() ? last_full_combine_ms : last_partial_combine_ms; }
  double last_gpu_pass_ms = -1;                   // a GPU level-1 pass cannot stop at a deadline

  void build_grid() {
    const auto dims = lighting::Level0Grid::choose_dims(mesh->bounds, opt.level0_resolution,
                                                        opt.level0_memory_budget_bytes, std::max<std::size_t>(1, lights.size()));
    grid = lighting::Level0Grid(*mesh, dims, opt.occluders);
    if (gpu) gpu->set_grid(grid);
    step = opt.level1_step > 0 ? opt.level1_step : std::max(topology.mean_edge, grid.max_spacing());
    resample_pending = has_field;
    mark_all();
    for (auto& l : lights) l.forget_direction();  // the step sets the vertex groups
  }
  // The light colour in the caller's point order (light_rho's copies are made when asked for).
  // Returns whether every point was copied.
  bool publish() {
    const std::size_t np = point_order.size();
    auto copy_out = [&](std::size_t i) {
      const auto p = static_cast<std::size_t>(point_order[i]);
      for (int c = 0; c < 3; ++c) rgb_out[3 * p + c] = rgb[3 * i + c];
    };
    const bool all = publish_takes_all();
    if (all) {
      rgb_out.resize(3 * np);
      parallel_for(np, 1 << 14, [&](std::size_t b, std::size_t e) {
        for (std::size_t i = b; i < e; ++i) copy_out(i);
      });
    } else {
      parallel_for(published_points.size(), kPointsPerTask, [&](std::size_t b, std::size_t e) {
        for (std::size_t k = b; k < e; ++k) copy_out(static_cast<std::size_t>(published_points[k]));
      });
    }
    publish_all = false;
    published_points.clear();
    for (auto& l : lights) l.rho1_out_stale = true;
    return all;
  }
  void mark_all() {
    for (auto& l : lights) l.stage = LightState::Stage::level0;
  }
  void solve_level0(LightState& l, LightUpdateReport& report) {
    const auto t0 = Clock::now();
    std::vector<float> rho0 = std::move(l.rho0);  // its memory is reused
    if (gpu) {
      if (!l.gpu) l.gpu = gpu->new_light();
      gpu->solve_level0(*l.gpu, l.light, opt.sigma_a, rho0);
    } else {
      lighting::solve_level0(grid, l.light, opt.sigma_a, rho0, scratch0);
    }
    const std::size_t np = mesh->points.size();
    std::vector<float> at_vertex = std::move(at_vertex_scratch);
    at_vertex.resize(np);
    parallel_for(np, 4096, [&](std::size_t b, std::size_t e) {
      for (std::size_t p = b; p < e; ++p) at_vertex[p] = static_cast<float>(grid.sample(rho0, mesh->points[p]));
    });
    if (opt.mode == LightSolveMode::level0_only || !l.has_solution) {
      l.rho1 = at_vertex;
    } else {
      // Warm start: keep the previous level-1 detail, scaled by how level 0 changed.
      parallel_for(np, 1 << 14, [&](std::size_t b, std::size_t e) {
        for (std::size_t p = b; p < e; ++p) {
          const double before = l.rho0_vertex[p];
          const double v = before > 1e-6 ? l.rho1[p] * (at_vertex[p] / before) : at_vertex[p];
          l.rho1[p] = static_cast<float>(std::clamp(v, 0.0, 1.0));
        }
      });
    }
    l.rho0 = std::move(rho0);
    at_vertex_scratch = std::move(l.rho0_vertex);
    l.rho0_vertex = std::move(at_vertex);
    l.has_solution = true;
    l.gpu_rho1_stale = true;
    l.pass_state.clear();  // the vertex order and start tets depend only on the light: kept
    l.passes = 0;
    l.residual = HUGE_VAL;
    l.converged = opt.mode == LightSolveMode::level0_only;
    l.stage = opt.mode == LightSolveMode::level0_only ? LightState::Stage::done : LightState::Stage::level1;
    combine_pending = true;
    ++report.lights_recomputed;
    report.l0_prop_ms += ms_since(t0);
  }
  // Whether the level-1 walks are recorded: they fit in the walk memory budget.
  bool record_walks() const { return record_walks(lights.size()); }
  bool record_walks(std::size_t light_count) const {
    return static_cast<double>(mesh->points.size()) * static_cast<double>(light_count) * kWalkBytesPerPoint <=
           static_cast<double>(opt.walk_memory_budget_bytes);
  }
  // The vertices grouped along the light, kept while the light stays.
  void ensure_order(LightState& l) {
    if (l.order_valid) return;
    l.order = lighting::order_vertices(*mesh, topology, l.light, step, std::move(l.order));
    // The per-vertex walk state too: allocating it (12 MB at 1M tets) inside the first batch of
    // a pass overran the frame that also built the order.
    l.pass_state.prepare_walks(mesh->points.size(), !gpu && record_walks());
    l.order_valid = true;
    if (gpu) gpu->set_order(*l.gpu, l.order);
  }
  // Returns true when a whole pass finished (one work unit).
  bool level1_pass(LightState& l, LightUpdateReport& report, Clock::time_point deadline) {
    const auto t0 = Clock::now();
    ensure_order(l);
    lighting::Level1Context ctx{*mesh, topology, field, grid, opt.occluders, opt.sigma_a, step, opt.level1_adaptive_step};
    ctx.record_walks = record_walks();
    bool finished = true;
    if (gpu) {
      // A whole pass on the device (no deadline inside it).
      if (l.gpu_rho1_stale) gpu->set_rho1(*l.gpu, l.rho1);
      l.gpu_rho1_stale = false;
      std::size_t lost = 0;
      l.pass_state.residual = gpu->level1_pass(*l.gpu, l.light, ctx, l.rho1, lost);
      report.lost_traces += lost;
    } else {
      std::atomic<std::size_t> lost{0};
      finished = lighting::level1_pass(ctx, l.light, l.rho0, l.order, l.rho1, l.pass_state, lost, deadline);
      report.lost_traces += lost.load();
      // Listed once, however many passes and lights changed a point in this call, so that the
      // combination and the copy out can work on the points in parallel.
      if (listed.size() != mesh->points.size()) listed.assign(mesh->points.size(), 0);
      for (std::int32_t point : l.pass_state.changed_now) {
        std::uint8_t& mark = listed[static_cast<std::size_t>(point)];
        if (!mark) combine_points.push_back(point);
        mark = 1;
      }
    }
    if (gpu) combine_pending = true;
    report.l1_prop_ms += ms_since(t0);
    if (!finished) return false;
    // A pass moves the light by one step, so with steps far below an edge the change per pass
    // is tiny long before the steady state: the residual is scaled to a light travel of one
    // mean edge (with adaptive steps every step is at least two edges, and the scale is 1).
    const double travel_scale = opt.level1_adaptive_step ? 1.0 : std::max(1.0, topology.mean_edge / step);
    l.residual = l.pass_state.residual * travel_scale;
    ++l.passes;
    ++report.level1_passes;
    l.converged = l.residual <= opt.propagation_tolerance;
    if (l.converged || l.passes >= opt.level1_max_passes) l.stage = LightState::Stage::done;
    return true;
  }
  // The lights' sum at point p, channel c.
  float combined(std::size_t p, int c) const {
    float v = 0.0f;
    for (const auto& l : lights)
      if (l.has_solution) v += static_cast<float>(l.rho1[p] * l.light.color[c]);
    return v;
  }
  // Point value i of the combined source becomes v. Warm start: the previous scattered field
  // plus the change of its source (exact when the source changed by a constant; `before` is the
  // source it was scattered from); otherwise, the unscattered field.
  void set_source(std::size_t i, float v, float before, bool warm) {
    pre[i] = v;
    if (!warm) {
      rgb[i] = v;
    } else {
      const float delta = v - before;
      if (std::isfinite(delta)) rgb[i] += delta;
    }
  }
  void combine() {
    const bool scatter = scatters();
    if (!combine_is_full()) {
      // Only the points a level-1 call changed (a frame's share of a pass: a few percent of
      // them), each updated as by combine_all.
      parallel_for(combine_points.size(), kPointsPerTask, [&](std::size_t b, std::size_t e) {
        for (std::size_t k = b; k < e; ++k) {
          const auto p = static_cast<std::size_t>(combine_points[k]);
          for (int c = 0; c < 3; ++c) set_source(3 * p + c, combined(p, c), pre[3 * p + c], scatter);
          listed[p] = 0;
        }
      });
      published_points.insert(published_points.end(), combine_points.begin(), combine_points.end());
      combine_points.clear();
      source_changed(scatter);
      return;
    }
    combine_all(scatter);
  }
  // The scattering starts over from the new source; its tolerance's scale is recomputed when it
  // starts (update_pre_scale).
  void source_changed(bool scatter) {
    has_rgb = true;
    pre_scale_stale = true;
    scatter_done = !scatter;
    scatter_converged = !scatter;
    scatter_residual = scatter ? HUGE_VAL : 0.0;
    scatter_iterations = 0;
    combine_pending = false;
    gpu_scatter_stale = true;
    cpu_scatter_stale = true;
    solve.restart();
  }
  void combine_all(bool scatter) {
    // Runs inside a frame's budget: parallel, and into kept buffers (a fresh 12-byte-per-point
    // vector each time cost page faults on top of the arithmetic).
    const std::size_t np = mesh->points.size();
    for (std::int32_t point : combine_points) listed[static_cast<std::size_t>(point)] = 0;
    combine_points.clear();
    publish_all = true;
    previous_pre.swap(pre);
    pre.resize(3 * np);
    const bool warm = scatter && has_rgb && previous_pre.size() == pre.size();
    if (!warm) rgb.resize(3 * np);
    parallel_for(np, 1 << 14, [&](std::size_t b, std::size_t e) {
      for (std::size_t p = b; p < e; ++p)
        for (int c = 0; c < 3; ++c) {
          const std::size_t i = 3 * p + c;
          set_source(i, combined(p, c), warm ? previous_pre[i] : 0.0f, warm);
        }
    });
    source_changed(scatter);
  }
  // The CPU scattering's set-up, a budget piece of its own: the source and the start in the
  // plan's order, the tolerance's scale, which sources are finite. Returns its duration.
  double scatter_setup() {
    const auto t0 = Clock::now();
    update_pre_scale();
    lighting::to_plan_order(scatter_plan, pre, pre_planned);
    lighting::to_plan_order(scatter_plan, rgb, rgb_planned);
    lighting::scatter_prepare(scatter_plan, pre_planned, rgb_planned, solve);
    cpu_scatter_stale = false;
    return ms_since(t0);
  }
  // Scattering on the CPU: its arrays are allocated at construction and the set-up timed on them
  // (the second of two runs, past the first touch of its memory), so that a budgeted first
  // scattering plans its set-up with other work instead of waiting for a call of its own.
  void prime_scatter_setup() {
    pre.assign(rgb.size(), 0.0f);
    for (int run = 0; run < 2; ++run) {
      pre_scale_stale = true;
      last_scatter_setup_ms = scatter_setup();
    }
    pre_scale_stale = true;
    cpu_scatter_stale = true;
    solve.restart();
  }
  // The first light's memory, allocated and touched when the volume is built, as the
  // scattering's is: its level-0 light, vertex order, walk state and recorded crossings (about
  // kCrossingsPerWalk per point), all sized by the mesh. Its first frames then spend their budget
  // on the solve instead of on page faults (17 000 at 1M tets, about 11 ms of a 140 ms cold
  // start on two cores). set_lights hands it to the first light it adds.
  void prime_first_light() {
    const std::size_t np = mesh->points.size();
    LightState& l = first_light;
    for (auto* v : {&l.rho0_vertex, &l.rho1, &at_vertex_scratch}) lighting::reserve_touched(*v, np);
    lighting::reserve_touched(l.rho0, grid.size());
    if (opt.mode != LightSolveMode::level0_only) {
      l.order.reserve(np);
      l.pass_state.reserve(np, record_walks(1), kCrossingsPerWalk * np);
      const lighting::Level1Context ctx{*mesh, topology, field, grid, opt.occluders, opt.sigma_a, step, opt.level1_adaptive_step};
      lighting::prime_pass_timing(ctx, l.pass_state);
    }
    first_light_ready = true;
  }
  // A CPU level-0 solve timed at construction (the grid has no field yet; a light along -z), so
  // that a new volume's first call can follow its resampling with its first light's level-0
  // piece instead of leaving the rest of that call unused.
  void prime_level0() {
    LightState probe;
    probe.light = Light{Light::Kind::directional, {0, 0, -1}, {1, 1, 1}};
    LightUpdateReport unused;
    const auto t0 = Clock::now();
    solve_level0(probe, unused);
    last_level0_ms = ms_since(t0);
    // The solve left its vertex values with the probe and the probe's empty array as the
    // scratch: the scratch takes the filled one back, not to be lost with the probe.
    at_vertex_scratch = std::move(probe.rho0_vertex);
  }
  // The largest finite |pre|, the scale of the scattering's tolerance.
  void update_pre_scale() {
    if (!pre_scale_stale) return;
    constexpr std::size_t kChunk = 1 << 16;
    std::vector<double> scale((pre.size() + kChunk - 1) / kChunk, 0.0);
    parallel_for(pre.size(), kChunk, [&](std::size_t b, std::size_t e) {
      double m = 0;
      for (std::size_t i = b; i < e; ++i)
        if (std::isfinite(pre[i])) m = std::max(m, static_cast<double>(std::fabs(pre[i])));
      scale[b / kChunk] = m;
    });
    pre_scale = scale.empty() ? 0.0 : *std::max_element(scale.begin(), scale.end());
    pre_scale_stale = false;
  }
};

LightVolume::LightVolume(std::shared_ptr<const TetMesh> mesh, LightVolumeOptions options)
    : m_impl(std::make_unique<Impl>()) {
  require(mesh != nullptr, "LightVolume: mesh is null; expected a prepared TetMesh");
  require(!mesh->tets.empty(), "LightVolume: the mesh has no tets; expected at least one");
  check_options(options);
  Impl& im = *m_impl;
  im.point_order = detail::morton_point_order(*mesh);
  im.mesh = std::make_shared<const TetMesh>(detail::with_points_in_order(*mesh, im.point_order));
  im.opt = std::move(options);
  im.topology = lighting::Level1Topology(*im.mesh);
  im.scatter_weights = lighting::scatter_weights(*im.mesh, im.topology);
  im.scatter_plan = lighting::plan_scatter(*im.mesh, im.topology, im.scatter_weights);
  if (im.opt.device)
    im.gpu = std::make_unique<lighting::GpuLightSolver>(im.opt.device, *im.mesh, im.topology, im.scatter_weights,
                                                        im.opt.occluders);
  im.build_grid();
  im.rgb.assign(3 * im.mesh->points.size(), 0.0f);
  im.rgb_out = im.rgb;
  if (!im.gpu) im.prime_level0();
  if (!im.gpu && im.scatters()) im.prime_scatter_setup();
  if (!im.gpu) im.prime_first_light();
}

LightVolume::~LightVolume() = default;
LightVolume::LightVolume(LightVolume&&) noexcept = default;
LightVolume& LightVolume::operator=(LightVolume&&) noexcept = default;

void LightVolume::set_field(const std::vector<float>& point_scalars, const TransferFunction& tf) {
  Impl& im = *m_impl;
  require(point_scalars.size() == im.mesh->points.size(),
          "LightVolume::set_field: point_scalars has " + std::to_string(point_scalars.size()) +
              " values but the mesh has " + std::to_string(im.mesh->points.size()) + " points; expected one per point");
  tf.validate();
  im.scalars.resize(point_scalars.size());
  for (std::size_t i = 0; i < im.scalars.size(); ++i) im.scalars[i] = point_scalars[static_cast<std::size_t>(im.point_order[i])];
  im.field.build(im.scalars, tf);
  im.has_field = true;
  im.resample_pending = true;
  im.mark_all();
}

void LightVolume::set_lights(std::vector<Light> lights) {
  Impl& im = *m_impl;
  for (std::size_t i = 0; i < lights.size(); ++i) check_light(lights[i], i);
  const bool regrow = lighting::Level0Grid::bytes_per_node(lights.size()) * im.grid.size() > im.opt.level0_memory_budget_bytes;
  std::vector<Impl::LightState> next(lights.size());
  for (std::size_t i = 0; i < lights.size(); ++i) {
    if (i < im.lights.size()) {
      Impl::LightState& old = im.lights[i];
      Light same_colour = lights[i];
      same_colour.color = old.light.color;
      const bool moved = !(same_colour == old.light);
      next[i] = std::move(old);
      if (moved) {
        next[i].stage = Impl::LightState::Stage::level0;
        next[i].forget_direction();
      }
    } else if (im.first_light_ready) {
      next[i] = std::move(im.first_light);
      im.first_light_ready = false;
    }
    next[i].light = lights[i];
  }
  im.lights = std::move(next);
  im.combine_pending = true;
  if (regrow) im.build_grid();  // fewer nodes per light so the budget still holds
}

void LightVolume::set_absorption(double sigma_a) {
  require(std::isfinite(sigma_a) && sigma_a >= 0,
          "LightVolume::set_absorption: sigma_a = " + std::to_string(sigma_a) + "; expected a finite value >= 0");
  m_impl->opt.sigma_a = sigma_a;
  m_impl->mark_all();
}

void LightVolume::set_scattering(std::array<double, 3> sigma_s) {
  for (double s : sigma_s)
    require(std::isfinite(s) && s >= 0,
            "LightVolume::set_scattering: sigma_s has " + std::to_string(s) + "; expected finite values >= 0");
  m_impl->opt.sigma_s = sigma_s;
  m_impl->combine_pending = true;
}

LightUpdateReport LightVolume::update(const LightBudget& budget) {
  Impl& im = *m_impl;
  if (!im.has_field)
    throw Error(ErrorCode::invalid_operation, "LightVolume::update: no field yet; call set_field first");
  const auto t0 = Clock::now();
  LightUpdateReport report;
  bool did_work = false;
  if (im.resample_pending) {
    const auto tr = Clock::now();
    im.grid.resample(*im.mesh, im.scalars, im.field.table);
    if (im.gpu) im.gpu->set_field(im.grid, im.field);
    im.resample_pending = false;
    report.resample_ms = ms_since(tr);
    did_work = true;
  }
  // Room kept for what ends the call: copying the results out (see the scattering below).
  double reserve_ms = im.expected_publish_ms();
  // A piece of work starts only if it is expected (from its last duration) to end within the
  // time budget; the first piece of a call always starts, so every call makes progress.
  // A piece never timed yet (expected_ms < 0) starts only as the first of a call.
  auto allowed = [&](double expected_ms) {
    if (budget.max_work_units >= 0 && report.work_units >= budget.max_work_units) return false;
    if (expected_ms < 0) return !did_work || !std::isfinite(budget.max_ms);
    return !did_work || ms_since(t0) + expected_ms + reserve_ms < budget.max_ms;
  };
  using Stage = Impl::LightState::Stage;
  for (auto& l : im.lights) {
    if (l.stage != Stage::level0) continue;
    // A light that moved also needs its vertex order: built in the same piece, so that a new
    // light does not spend a frame on each of two pieces never timed before.
    const bool with_order = !l.order_valid && !im.gpu;
    if (!allowed(im.last_level0_ms + (with_order ? std::max(0.0, im.last_order_ms) : 0.0))) break;
    const auto tl = Clock::now();
    im.solve_level0(l, report);
    im.last_level0_ms = ms_since(tl);
    if (with_order) {
      const auto to = Clock::now();
      im.ensure_order(l);
      im.last_order_ms = ms_since(to);
      report.l1_prop_ms += im.last_order_ms;
    }
    ++report.work_units;
    did_work = true;
  }
  const std::size_t mesh_points = im.mesh->points.size();
  const auto deadline =
      std::isfinite(budget.max_ms)
          ? t0 + std::chrono::duration_cast<Clock::duration>(
                     std::chrono::duration<double, std::milli>(budget.max_ms - im.expected_combine_ms() - im.expected_publish_ms()))
          : Clock::time_point::max();
  for (auto& l : im.lights)
    while (l.stage == Stage::level1) {
      if (!l.order_valid && !im.gpu) {  // a piece of its own: it cannot stop at the deadline
        if (!allowed(im.last_order_ms)) break;
        const auto to = Clock::now();
        im.ensure_order(l);
        im.last_order_ms = ms_since(to);
        report.l1_prop_ms += im.last_order_ms;
        did_work = true;
        continue;
      }
      // A CPU pass stops at the deadline by itself, after pieces it sizes to fit (batches down
      // to kLevel1MinBatch vertices, slices of start hints); it starts only with room for its
      // first piece, and a full pass also for its set-up (unknown: only as the first piece of a
      // call).
      const auto& ps = l.pass_state;
      const bool starts_full = !ps.in_pass && ps.departure_corners.size() != mesh_points;
      double expected = ps.vertex_ms < 0 ? -1.0
                                         : std::max(ps.vertex_ms * static_cast<double>(lighting::kLevel1MinBatch),
                                                    starts_full || ps.hint_next < ps.hint_end ? ps.hint_slice_ms : 0.0);
      if (starts_full && expected >= 0) expected = ps.full_setup_ms < 0 ? -1.0 : expected + ps.full_setup_ms;
      if (!allowed(im.gpu ? im.last_gpu_pass_ms : expected)) break;
      const auto tp = Clock::now();
      if (im.level1_pass(l, report, deadline)) ++report.work_units;
      if (im.gpu) im.last_gpu_pass_ms = ms_since(tp);
      did_work = true;
    }
  bool combined = false;
  if (im.combine_pending || !im.combine_points.empty()) {
    const auto tc = Clock::now();
    const bool full = im.combine_is_full();
    im.combine();
    (full ? im.last_full_combine_ms : im.last_partial_combine_ms) = ms_since(tc);
    combined = true;
  }
  // Scattering waits for the lights: every level-1 pass changes its source and restarts it, so
  // iterations run before the last pass would be thrown away. Until then light_rgb() holds the
  // unscattered estimate plus the last scattering's correction (see combine()).
  bool lights_settled = true;
  for (const auto& l : im.lights) lights_settled = lights_settled && l.stage == Stage::done;
  if (!im.scatter_done && lights_settled) {
    const auto ts = Clock::now();
    // A frame that scatters ends with the iterate copied back to point order and every point
    // copied out, not only those a level-1 piece changed: the budget holds room for both.
    reserve_ms = im.last_full_publish_ms + (im.gpu ? 0.0 : im.last_copy_back_ms);
    bool gpu_ran = false, cpu_ran = false;
    while (!im.scatter_done) {
      if (!im.gpu && im.cpu_scatter_stale) {
        if (!allowed(im.last_scatter_setup_ms)) break;
        im.last_scatter_setup_ms = im.scatter_setup();
        did_work = true;
        cpu_ran = true;
        continue;
      }
      // The iterates are stored in float, and an iteration that reads only the previous iterate
      // settles within a few units in the last place, not on an exact fixed point: a tolerance
      // below 16 of them (1e-6 relative) is raised to that.
      im.update_pre_scale();
      const double tolerance = std::max(im.opt.scatter_tolerance, kScatterToleranceFloor) * std::max(im.pre_scale, 1e-300);
      // The CPU sweeps in pieces of whole blocks (two or more, one per core): as many as the
      // budget has room for, timed per block; the GPU runs whole iterations.
      std::size_t chunks = lighting::kScatterChunks - im.solve.next_chunk;
      if (!im.gpu && im.last_chunk_ms < 0 && std::isfinite(budget.max_ms)) {
        // Never timed: one block (1/16 of an iteration) as a probe, which any room left will do.
        if (!allowed(0.0)) break;
        chunks = 1;
      } else if (im.gpu || !std::isfinite(budget.max_ms)) {
        if (!allowed(im.gpu ? im.last_sweep_ms : im.last_chunk_ms < 0 ? -1.0 : im.last_chunk_ms * chunks)) break;
      } else {
        if (!allowed(0.0)) break;  // the work-unit cap
        const double room = budget.max_ms - ms_since(t0) - reserve_ms;
        const auto fit = static_cast<std::size_t>(std::max(0.0, room / im.last_chunk_ms));
        if (did_work && fit < 2) break;
        chunks = std::min(chunks, std::max<std::size_t>(fit, 2));
      }
      const auto tw = Clock::now();
      did_work = true;
      int ran = 1;
      if (im.gpu) {
        // A batch of iterations, never more than the cap or the work units left.
        if (im.gpu_scatter_stale) im.gpu->set_scatter_source(im.pre, im.rgb);
        im.gpu_scatter_stale = false;
        int most = im.opt.scatter_max_iterations - im.scatter_iterations;
        if (budget.max_work_units >= 0) most = std::min(most, budget.max_work_units - report.work_units);
        ran = im.gpu->scatter(most, tolerance, im.opt.sigma_s, im.scatter_residual);
        gpu_ran = true;
      } else {
        const bool whole = lighting::scatter_iteration_part(im.scatter_plan, im.pre_planned, im.opt.sigma_s,
                                                            im.rgb_planned, im.solve, chunks);
        cpu_ran = true;
        im.last_chunk_ms = ms_since(tw) / static_cast<double>(chunks);
        if (!whole) continue;
        im.scatter_residual = im.solve.residual;
      }
      im.last_sweep_ms = ms_since(tw);
      im.scatter_iterations += ran;
      report.scatter_iterations += ran;
      report.work_units += ran;
      im.scatter_converged = im.scatter_residual <= tolerance;
      if (im.scatter_converged || im.scatter_iterations >= im.opt.scatter_max_iterations) im.scatter_done = true;
    }
    if (gpu_ran) im.gpu->read_scatter(im.rgb);
    if (cpu_ran) {
      const auto tb = Clock::now();
      lighting::to_point_order(im.scatter_plan, im.rgb_planned, im.rgb);
      im.last_copy_back_ms = ms_since(tb);
    }
    im.publish_all = im.publish_all || gpu_ran || cpu_ran;
    report.l1_scatter_ms += ms_since(ts);
  }
  // Converged: every stage finished at its tolerance. A stage stopped by its iteration cap is
  // finished (nothing more will run until something changes) but not converged.
  report.converged = im.scatter_done && im.scatter_converged;
  report.residual = 0;
  for (const auto& l : im.lights)
    if (l.stage != Stage::done || !l.converged) {
      report.converged = false;
      report.residual = std::max(report.residual, l.residual);
    }
  if (!im.scatter_converged) report.residual = std::max(report.residual, im.scatter_residual);
  if (did_work || combined) {
    const auto tp = Clock::now();
    const bool full = im.publish();
    (full ? im.last_full_publish_ms : im.last_partial_publish_ms) = ms_since(tp);
  }
  report.total_ms = ms_since(t0);
  return report;
}

const std::vector<float>& LightVolume::light_rgb() const { return m_impl->rgb_out; }

const std::vector<float>& LightVolume::light_rho(std::size_t k) const {
  require(k < m_impl->lights.size(), "LightVolume::light_rho: light " + std::to_string(k) + " does not exist");
  const Impl& im = *m_impl;
  const auto& l = im.lights[k];
  if (l.rho1_out_stale) {
    l.rho1_out.resize(l.rho1.size());
    for (std::size_t i = 0; i < l.rho1.size(); ++i) l.rho1_out[static_cast<std::size_t>(im.point_order[i])] = l.rho1[i];
    l.rho1_out_stale = false;
  }
  return l.rho1_out;
}

const std::vector<float>& LightVolume::level0_rho(std::size_t k) const {
  require(k < m_impl->lights.size(), "LightVolume::level0_rho: light " + std::to_string(k) + " does not exist");
  return m_impl->lights[k].rho0;
}

Level0View LightVolume::level0() const {
  const auto& g = m_impl->grid;
  return {g.dims(), g.lo(), g.spacing(), &g.mask(), &g.tau()};
}

std::array<int, 3> LightVolume::level0_dims() const { return m_impl->grid.dims(); }
double LightVolume::level1_step() const { return m_impl->step; }
double LightVolume::mean_edge_length() const { return m_impl->topology.mean_edge; }
const LightVolumeOptions& LightVolume::options() const { return m_impl->opt; }

}  // namespace penumbra::render

// SPDX-License-Identifier: BSD-3-Clause
// render/src/lighting/light_volume.cpp -- Algorithm 1: the light volume's incremental updates
#include "penumbra/render/light_volume.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

#include "cpu_light_solver.h"
#include "device_light_solver.h"
#include "level0_grid.h"
#include "level1_mesh.h"
#include "level1_solve.h"
#include "light_combination.h"
#include "light_scattering.h"
#include "light_schedule.h"
#include "light_solver.h"
#include "light_state.h"
#include "penumbra/core/elapsed.h"
#include "penumbra/core/error.h"
#include "penumbra/core/thread_pool.h"
#include "tet_order.h"

namespace penumbra::render {
namespace {

using lighting::Clock;
using lighting::LightSchedule;
using lighting::LightState;
using Stage = LightState::Stage;

// A recorded level-1 walk (PassState::walks) per point: the 56-byte record and about
// kCrossingsPerWalk crossings of 28 B in the light's arena.
constexpr std::size_t kCrossingsPerWalk = 8;
constexpr double kWalkBytesPerPoint = 320.0;

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
  const Bounds& b = o.level0_bounds;
  bool finite = true;
  for (int a = 0; a < 3; ++a) finite = finite && std::isfinite(b.lo[a]) && std::isfinite(b.hi[a]);
  require(b.empty() || (finite && b.lo.y <= b.hi.y && b.lo.z <= b.hi.z),
          call + "level0_bounds is not finite or has lo > hi on some axis; expected empty or finite lo <= hi");
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

// Where the scattering of the current source stands.
struct ScatterProgress {
  int iterations = 0;
  double residual = HUGE_VAL;  // the last finished iteration's largest change
  bool converged = false;      // the last change is within the tolerance
  bool done = false;           // converged, or stopped by the iteration cap, or nothing to scatter
};

}  // namespace

struct LightVolume::Impl {
  // The caller's mesh with its points renumbered along a Morton curve: the walks, the scattering
  // and every per-point array run in that order, where the points of nearby tets sit nearby in
  // memory. Point i here is the caller's point point_order[i]; results are copied back to the
  // caller's order at the end of every update.
  std::vector<std::int32_t> point_order;
  LightVolumeOptions opt;
  // Its bounds span opt.level0_bounds too: the level-0 grid and the path lengths to the bounds
  // (level1_solve.h) are then the same on every rank of a split mesh.
  std::shared_ptr<const TetMesh> mesh;
  lighting::Level1Topology topology;
  lighting::Level0Grid grid;
  lighting::Level1Field field;
  std::vector<float> scalars;
  double step = 0;
  bool has_field = false, resample_pending = false;
  // combine_level0 replaced the grid's extinction (and mask) since the solver last read them.
  bool upload_pending = false, grid_upload_pending = false;
  std::unique_ptr<lighting::LightSolver> solver;
  std::vector<LightState> lights;
  lighting::LightCombination combination;
  ScatterProgress scattering;
  std::vector<float> at_vertex_scratch;  // a level-0 solve's values at the points, before a light takes them
  // The working memory of the first light set, allocated with the volume (prime_first_light).
  LightState first_light;
  bool first_light_ready = false;
  // The last durations of the volume's own pieces (ms; < 0: never timed).
  double level0_ms = -1, order_ms = -1;
  // The resampling combine_level0 did since the last update (reported as that update's).
  double combine_resample_ms = 0;

  Impl(const TetMesh& caller_mesh, LightVolumeOptions options)
      : point_order(detail::morton_point_order(caller_mesh)),
        opt(std::move(options)),
        mesh(in_solve_order(caller_mesh)),
        topology(*mesh),
        combination(mesh->points.size()) {
    lighting::CpuLightSolver* cpu = make_solver();
    build_grid();
    if (cpu) prime(*cpu);
  }

  // The solver of the mesh as it is now: on opt.device, else on the CPU (returned, for priming).
  lighting::CpuLightSolver* make_solver() {
    const std::vector<float> weights = lighting::scatter_weights(*mesh, topology);
    if (opt.device) {
      solver = std::make_unique<lighting::DeviceLightSolver>(opt.device, *mesh, topology, weights, opt.occluders);
      return nullptr;
    }
    auto cpu = std::make_unique<lighting::CpuLightSolver>(*mesh, topology, weights);
    lighting::CpuLightSolver* made = cpu.get();
    solver = std::move(cpu);
    return made;
  }

  // The same mesh with its points moved: the point order, the walk records and each light's
  // solution are kept; the edge lengths, the solver's positions and scattering weights and the
  // level-0 grid follow the points. Every light then starts again from its level-0
  // solve, as a light that moved does, with its level-1 solution as the warm start
  // (LightState::take_level0); the recorded walks are forgotten and the start tets become hints.
  std::shared_ptr<const TetMesh> in_solve_order(const TetMesh& caller_mesh) const {
    TetMesh ordered = detail::with_points_in_order(caller_mesh, point_order);
    if (!opt.level0_bounds.empty()) {
      ordered.bounds.extend(opt.level0_bounds.lo);
      ordered.bounds.extend(opt.level0_bounds.hi);
    }
    return std::make_shared<const TetMesh>(std::move(ordered));
  }
  void move_to(const TetMesh& moved) {
    mesh = in_solve_order(moved);
    topology.measure_edges(*mesh);
    solver->move_points(*mesh, topology, lighting::scatter_weights(*mesh, topology));
    build_grid();
  }

  bool scatters() const { return opt.sigma_s[0] > 0 || opt.sigma_s[1] > 0 || opt.sigma_s[2] > 0; }
  // Whether the level-1 walks of `light_count` lights fit in the walk memory budget.
  bool record_walks(std::size_t light_count) const {
    return static_cast<double>(mesh->points.size()) * static_cast<double>(light_count) * kWalkBytesPerPoint <=
           static_cast<double>(opt.walk_memory_budget_bytes);
  }
  lighting::Level1Context level1_context() const {
    lighting::Level1Context ctx{*mesh, topology, field, grid, opt.occluders, opt.sigma_a, step, opt.level1_adaptive_step};
    ctx.record_walks = record_walks(lights.size());
    return ctx;
  }
  void mark_all() {
    for (auto& l : lights) l.stage = Stage::level0;
  }
  void build_grid() {
    const auto dims = lighting::Level0Grid::choose_dims(mesh->bounds, opt.level0_resolution,
                                                        opt.level0_memory_budget_bytes, std::max<std::size_t>(1, lights.size()));
    grid = lighting::Level0Grid(*mesh, mesh->bounds, dims, opt.occluders);
    solver->set_grid(grid);
    step = opt.level1_step > 0 ? opt.level1_step : std::max(topology.mean_edge, grid.max_spacing());
    resample_pending = has_field;
    mark_all();
    for (auto& l : lights) l.forget_direction();  // the step sets the vertex groups
  }

  // The CPU solve plans its pieces from their timings, so a new volume times them now, on the
  // memory they will use, so that its first calls spend their budget on the solve: the level-0
  // solve, the scattering's set-up and the first light's first level-1 pieces.
  void prime(lighting::CpuLightSolver& cpu) {
    prime_level0();
    if (scatters()) cpu.time_scatter_setup(combination);
    prime_first_light();
  }
  // A level-0 solve of a light along -z on the grid without a field, so that a new volume's
  // first call can follow its resampling with its first light's level-0 piece.
  void prime_level0() {
    LightState probe;
    probe.light = Light{Light::Kind::directional, {0, 0, -1}, {1, 1, 1}};
    LightUpdateReport unused;
    level0_ms = lighting::timed_ms([&] { solve_level0(probe, unused); });
    // The probe took the filled values at the points and left its empty array as the scratch:
    // the scratch takes the filled one back, not to be lost with the probe.
    at_vertex_scratch = std::move(probe.rho0_vertex);
  }
  // The first light's memory, allocated and touched: its level-0 light, vertex order, walk state
  // and recorded crossings (about kCrossingsPerWalk per point), all sized by the mesh, and its
  // first pass's timings. set_lights hands it to the first light it adds.
  void prime_first_light() {
    const std::size_t np = mesh->points.size();
    LightState& l = first_light;
    for (auto* v : {&l.rho0_vertex, &l.rho1, &at_vertex_scratch}) lighting::reserve_touched(*v, np);
    lighting::reserve_touched(l.rho0, grid.size());
    if (opt.mode != LightSolveMode::level0_only) {
      l.order.reserve(np);
      l.pass_state.reserve(np, record_walks(1), kCrossingsPerWalk * np);
      lighting::prime_pass_timing(level1_context(), l.pass_state);
    }
    first_light_ready = true;
  }

  void resample_if_pending(LightSchedule& schedule, LightUpdateReport& report) {
    if (!resample_pending && !upload_pending) return;
    report.resample_ms += lighting::timed_ms([&] {
      if (resample_pending) grid.resample(*mesh, scalars, field.table);
      if (grid_upload_pending) solver->set_grid(grid);
      solver->set_field(grid, field);
    });
    resample_pending = upload_pending = grid_upload_pending = false;
    schedule.ran_piece(0);
  }
  void combine_level0(const LightVolume::Level0Combine& combine) {
    const double ms = lighting::timed_ms([&] {
      if (resample_pending) grid.resample(*mesh, scalars, field.table);
      resample_pending = false;
      if (grid.combine(combine)) grid_upload_pending = true;
    });
    upload_pending = true;
    combine_resample_ms += ms;
  }

  // Level 0 interpolated at every mesh point, into at_vertex_scratch.
  void sample_level0_at_points(const std::vector<float>& rho0) {
    at_vertex_scratch.resize(mesh->points.size());
    parallel_for(at_vertex_scratch.size(), 4096, [&](std::size_t b, std::size_t e) {
      for (std::size_t p = b; p < e; ++p) at_vertex_scratch[p] = static_cast<float>(grid.sample(rho0, mesh->points[p]));
    });
  }
  void solve_level0(LightState& l, LightUpdateReport& report) {
    const auto start = Clock::now();
    std::vector<float> rho0 = std::move(l.rho0);  // its memory is reused
    solver->solve_level0(l, grid, opt.sigma_a, rho0);
    sample_level0_at_points(rho0);
    l.take_level0(std::move(rho0), at_vertex_scratch, opt.mode);
    combination.recombine_all();
    ++report.lights_recomputed;
    report.l0_prop_ms += ms_since(start);
  }
  // Light l's level-0 solve: one work unit. A light that moved also needs its vertex order,
  // built in the same piece where the order is a piece of its own, so that a new light does not
  // spend a call on each of two pieces never timed before.
  bool level0_piece(LightState& l, LightSchedule& schedule, LightUpdateReport& report) {
    const bool with_order = !l.order_valid && solver->orders_apart();
    if (!schedule.allows(level0_ms + (with_order ? std::max(0.0, order_ms) : 0.0))) return false;
    level0_ms = lighting::timed_ms([&] { solve_level0(l, report); });
    if (with_order) build_order(l, report);
    schedule.ran_piece(1);
    return true;
  }
  void build_order(LightState& l, LightUpdateReport& report) {
    order_ms = lighting::timed_ms([&] { solver->prepare_order(l, level1_context()); });
    report.l1_prop_ms += order_ms;
  }

  // The next level-1 piece of light l, if the schedule allows it: its vertex order (which cannot
  // stop at the deadline) or its pass, up to the deadline. A finished pass is one work unit.
  bool level1_piece(LightState& l, LightSchedule& schedule, Clock::time_point deadline, LightUpdateReport& report) {
    if (!l.order_valid && solver->orders_apart()) {
      if (!schedule.allows(order_ms)) return false;
      build_order(l, report);
      schedule.ran_piece(0);
      return true;
    }
    if (!schedule.allows(solver->expected_level1_ms(l))) return false;
    schedule.ran_piece(level1_pass(l, deadline, report) ? 1 : 0);
    return true;
  }
  // Returns whether the pass finished.
  bool level1_pass(LightState& l, Clock::time_point deadline, LightUpdateReport& report) {
    const auto start = Clock::now();
    const lighting::Level1Piece piece = solver->level1_pass(l, level1_context(), deadline);
    report.lost_traces += piece.lost;
    if (piece.changed != nullptr)
      combination.mark_changed(*piece.changed);
    else
      combination.recombine_all();
    report.l1_prop_ms += ms_since(start);
    if (!piece.finished) return false;
    // A pass moves the light by one step, so with steps far below an edge the change per pass
    // is tiny long before the steady state: the change is scaled to a light travel of one mean
    // edge (with adaptive steps every step is at least two edges, and the scale is 1).
    const double travel_scale = opt.level1_adaptive_step ? 1.0 : std::max(1.0, topology.mean_edge / step);
    l.count_pass(l.pass_state.residual * travel_scale, opt.propagation_tolerance, opt.level1_max_passes);
    ++report.level1_passes;
    return true;
  }

  // Combines what changed into the scattering's source, which restarts the scattering.
  bool combine_if_changed() {
    if (!combination.has_changes()) return false;
    combination.combine(lights, scatters());
    const bool scatter = scatters();
    scattering = {0, scatter ? HUGE_VAL : 0.0, !scatter, !scatter};
    solver->restart_scattering();
    return true;
  }
  // Scattering waits for the lights: every level-1 pass changes its source and restarts it, so
  // iterations run before the last pass would be thrown away. Until then light_rgb() holds the
  // unscattered estimate plus the last scattering's correction (LightCombination's warm start).
  bool scattering_due() const {
    return !scattering.done && std::all_of(lights.begin(), lights.end(), [](const LightState& l) { return l.stage == Stage::done; });
  }
  void scatter(LightSchedule& schedule, LightUpdateReport& report) {
    const auto start = Clock::now();
    // A call that scatters ends with the iterate read back and every point copied out, not only
    // those a level-1 piece changed: the budget keeps room for both.
    schedule.keep_for_end(combination.full_publish_ms() + solver->expected_read_back_ms());
    bool ran = false;
    while (!scattering.done) {
      const lighting::ScatterPiece piece = solver->scatter_piece(
          schedule, combination,
          {opt.sigma_s, opt.scatter_tolerance, opt.scatter_max_iterations - scattering.iterations, scattering.residual});
      if (!piece.ran) break;
      ran = true;
      schedule.ran_piece(piece.iterations);
      if (piece.iterations > 0) count_scatter_iterations(piece, report);
    }
    if (ran) {
      solver->read_scattering(combination.colour());
      combination.publish_all_next();
    }
    report.l1_scatter_ms += ms_since(start);
  }
  void count_scatter_iterations(const lighting::ScatterPiece& piece, LightUpdateReport& report) {
    scattering.iterations += piece.iterations;
    report.scatter_iterations += piece.iterations;
    scattering.residual = piece.residual;
    scattering.converged = piece.residual <= combination.scatter_tolerance(opt.scatter_tolerance);
    scattering.done = scattering.converged || scattering.iterations >= opt.scatter_max_iterations;
  }

  // Converged: every stage finished at its tolerance. A stage stopped by its iteration cap is
  // finished (nothing more runs until something changes) but not converged.
  void report_progress(const LightSchedule& schedule, LightUpdateReport& report) const {
    report.work_units = schedule.units_spent();
    report.converged = scattering.done && scattering.converged;
    report.residual = 0;
    for (const auto& l : lights)
      if (l.stage != Stage::done || !l.converged) {
        report.converged = false;
        report.residual = std::max(report.residual, l.residual);
      }
    if (!scattering.converged) report.residual = std::max(report.residual, scattering.residual);
  }
  void publish() {
    combination.publish(point_order);
    for (auto& l : lights) l.rho1_out_stale = true;
  }
};

LightVolume::LightVolume(std::shared_ptr<const TetMesh> mesh, LightVolumeOptions options) {
  require(mesh != nullptr, "LightVolume: mesh is null; expected a prepared TetMesh");
  // With no tet (a rank's empty part), level 0 is still made and merged with the other ranks'.
  require(!mesh->tets.empty() || !options.level0_bounds.empty(),
          "LightVolume: the mesh has no tets; expected at least one, or level0_bounds to span");
  check_options(options);
  m_impl = std::make_unique<Impl>(*mesh, std::move(options));
}

LightVolume::~LightVolume() = default;
LightVolume::LightVolume(LightVolume&&) noexcept = default;
LightVolume& LightVolume::operator=(LightVolume&&) noexcept = default;

void LightVolume::move_points(std::shared_ptr<const TetMesh> moved) {
  Impl& im = *m_impl;
  require(moved != nullptr, "LightVolume::move_points: mesh is null; expected the moved mesh (move_tet_mesh)");
  require(moved->points.size() == im.mesh->points.size() && moved->tet_count() == im.mesh->tet_count(),
          "LightVolume::move_points: the moved mesh has " + std::to_string(moved->points.size()) + " points and " +
              std::to_string(moved->tet_count()) + " tets; the volume's has " + std::to_string(im.mesh->points.size()) +
              " and " + std::to_string(im.mesh->tet_count()) + ": make a new volume for a new mesh");
  im.move_to(*moved);
}

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

void LightVolume::combine_level0(const Level0Combine& combine) {
  require(static_cast<bool>(combine), "LightVolume::combine_level0: combine is empty; expected a function");
  if (!m_impl->has_field)
    throw Error(ErrorCode::invalid_operation, "LightVolume::combine_level0: no field yet; call set_field first");
  m_impl->combine_level0(combine);
}

void LightVolume::set_lights(std::vector<Light> lights) {
  Impl& im = *m_impl;
  for (std::size_t i = 0; i < lights.size(); ++i) check_light(lights[i], i);
  const bool regrow = lighting::Level0Grid::bytes_per_node(lights.size()) * im.grid.size() > im.opt.level0_memory_budget_bytes;
  std::vector<LightState> next(lights.size());
  for (std::size_t i = 0; i < lights.size(); ++i) {
    if (i < im.lights.size()) {
      LightState& old = im.lights[i];
      Light same_colour = lights[i];
      same_colour.color = old.light.color;
      const bool moved = !(same_colour == old.light);
      next[i] = std::move(old);
      if (moved) {
        next[i].stage = Stage::level0;
        next[i].forget_direction();
      }
    } else if (im.first_light_ready) {
      next[i] = std::move(im.first_light);
      im.first_light_ready = false;
    }
    next[i].light = lights[i];
  }
  im.lights = std::move(next);
  im.combination.recombine_all();
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
  m_impl->combination.recombine_all();
}

LightUpdateReport LightVolume::update(const LightBudget& budget) {
  Impl& im = *m_impl;
  if (!im.has_field)
    throw Error(ErrorCode::invalid_operation, "LightVolume::update: no field yet; call set_field first");
  LightUpdateReport report;
  // A part with no point (a rank of a run over several that holds no cell) has nothing to light.
  if (im.mesh->points.empty()) {
    report.converged = true;
    return report;
  }
  LightSchedule schedule(budget);
  report.resample_ms = std::exchange(im.combine_resample_ms, 0.0);
  im.resample_if_pending(schedule, report);
  schedule.keep_for_end(im.combination.expected_publish_ms());
  for (LightState& l : im.lights)
    if (l.stage == Stage::level0 && !im.level0_piece(l, schedule, report)) break;
  // A level-1 pass stops by itself in time for the combination and the copy out that end the call.
  const auto deadline = schedule.deadline(im.combination.expected_combine_ms() + im.combination.expected_publish_ms());
  for (LightState& l : im.lights)
    while (l.stage == Stage::level1 && im.level1_piece(l, schedule, deadline, report)) {
    }
  const bool combined = im.combine_if_changed();
  if (im.scattering_due()) im.scatter(schedule, report);
  im.report_progress(schedule, report);
  if (schedule.ran_any() || combined) im.publish();
  report.total_ms = schedule.elapsed_ms();
  return report;
}

const std::vector<float>& LightVolume::light_rgb() const { return m_impl->combination.published(); }

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

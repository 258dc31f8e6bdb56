// SPDX-License-Identifier: BSD-3-Clause
// insitu/src/context.cpp -- the run: mesh and fields in, each step through its stages (step_stages.h)
#include "context.h"
#include "prepared_mesh.h"

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <map>
#include <mutex>
#include <tuple>
#include <utility>

#include "atomic_file.h"
#include "field_stages.h"
#include "field_store.h"
#include "progress_log.h"
#include "ghost_cells.h"
#include "penumbra/core/mesh_validation.h"
#include "view_cameras.h"
#include "image_writer.h"
#include "penumbra/render/occlusion.h"
#include "penumbra/core/elapsed.h"
#include "penumbra/core/error.h"
#include "penumbra/render/camera.h"
#include "penumbra/render/cpu_ray_caster.h"
#include "penumbra/render/gpu_ray_caster.h"
#include "penumbra/render/image.h"
#include "penumbra/render/light_volume.h"
#include "rank_lighting.h"
#include "rank_scattering.h"
#include "shared_points.h"
#include "penumbra/render/tet_mesh.h"

namespace penumbra::insitu {
namespace {

using Clock = std::chrono::steady_clock;

void log_line(const std::string& line) { std::fprintf(stderr, "penumbra: %s\n", line.c_str()); }

/// The GPU context, one per process and EGL setting ($PNB_EGL_LIBRARY, $PNB_EGL_DEVICE), shared
/// by every Context: opening one costs time and device memory. Kept for the life of the process
/// (some drivers crash when a context is destroyed during static destruction). The device line
/// is logged when it is opened, and a software device is pointed out once.
std::shared_ptr<render::GpuDevice> process_gpu_device(bool require_hardware) {
  static std::mutex mutex;
  static auto* devices = new std::map<std::string, std::shared_ptr<render::GpuDevice>>();
  auto env = [](const char* name) {
    const char* v = std::getenv(name);
    return std::string(v ? v : "");
  };
  const std::string key = env("PNB_EGL_LIBRARY") + "\n" + env("PNB_EGL_DEVICE");
  std::lock_guard lock(mutex);
  auto& device = (*devices)[key];
  if (device && (!require_hardware || !device->info().software)) return device;
  render::GpuOptions options;
  options.require_hardware = require_hardware;
  options.log = log_line;
  device = render::GpuDevice::open(options);
  if (device->info().software)
    log_line("backend \"gpu\" runs on a software rasteriser (" + device->info().gl_renderer +
             "): the images are the GPU path's, the speed is a CPU's");
  return device;
}

/// Resolves the configured backend to the one that runs: cpu or gpu. Throws
/// Error(backend_unavailable) when "gpu" is asked for and cannot run.
Backend resolve_backend(Backend requested) {
  if (requested == Backend::cpu) return Backend::cpu;
  if (requested == Backend::gpu) {
    try {
      process_gpu_device(false);
    } catch (const Error& e) {
      throw Error(ErrorCode::backend_unavailable, std::string("config: backend \"gpu\" is not available: ") +
                                                      e.what() + "; use \"cpu\" or \"auto\"");
    }
    return Backend::gpu;
  }
  // auto: a hardware GPU if there is one, else the CPU path (llvmpipe would only be slower).
  if (!render::hardware_gpu_present()) {
    log_line("backend \"auto\": no hardware GPU found through EGL; rendering on the CPU");
    return Backend::cpu;
  }
  try {
    process_gpu_device(true);
    return Backend::gpu;
  } catch (const Error& e) {
    log_line(std::string("backend \"auto\": the GPU cannot be used (") + e.what() + "); rendering on the CPU");
    return Backend::cpu;
  }
}

// What a run over several ranks does not do yet: refused at creation, naming the key.
void check_rank_rules(const Config& c) {
  auto refuse = [](const std::string& what) {
    throw Error(ErrorCode::invalid_argument, "config: " + what + " is not available in a run over several ranks yet");
  };
  // Image space starts a shadow gap at every ray sample; the ranks exchange only the points' gaps.
  if (c.lighting && c.lighting->occlusion_model && c.lighting->occlusion.space == OcclusionSpace::image &&
      c.lighting->occlusion.shadows && !c.lighting->lights.empty())
    refuse("lighting.occlusion.space \"image\" with shadows (use \"points\" or \"volume\")");
}

// A cycle as two 32-bit halves, each exact in a double, so that reductions compare it exactly.
struct CycleHalves {
  double high, low;
};
CycleHalves halves_of(std::int64_t cycle) {
  const auto u = static_cast<std::uint64_t>(cycle);
  return {static_cast<double>(u >> 32), static_cast<double>(u & 0xffffffffu)};
}
std::int64_t cycle_of(double high, double low) {
  return static_cast<std::int64_t>((static_cast<std::uint64_t>(high) << 32) | static_cast<std::uint64_t>(low));
}

// Names the ranks whose time or cycle differs from rank 0's (collective: every rank that found
// the least and greatest to differ calls it).
std::string step_disagreement(RankGroup& group, double time, std::int64_t cycle) {
  const CycleHalves c = halves_of(cycle);
  const std::vector<double> all = group.all_gather({time, c.high, c.low});
  auto differs = [&](std::size_t r) { return !std::equal(all.begin() + 3 * r, all.begin() + 3 * r + 3, all.begin()); };
  auto step_of = [&](std::size_t r) {
    return "time " + format_number(all[3 * r]) + ", cycle " + std::to_string(cycle_of(all[3 * r + 1], all[3 * r + 2]));
  };
  std::string text = "pnb_execute: every rank must pass the same time and cycle;";
  for (std::size_t r = 1; 3 * r + 2 < all.size(); ++r)
    if (differs(r)) text += " rank " + std::to_string(r) + " passed " + step_of(r) + ";";
  return text + " rank 0 passed " + step_of(0);
}

}  // namespace

std::string ranks_text(const std::vector<RankGroup::Failure>& failed, int ranks) {
  std::vector<std::pair<std::string, std::string>> messages;  // message, its ranks
  for (const RankGroup::Failure& f : failed) {
    auto it = std::find_if(messages.begin(), messages.end(), [&](const auto& m) { return m.first == f.message; });
    if (it == messages.end()) it = messages.insert(messages.end(), {f.message, "rank"});
    it->second += (it->second == "rank" ? " " : ", ") + std::to_string(f.rank);
  }
  if (messages.size() == 1 && static_cast<int>(failed.size()) == ranks) return messages.front().first;
  std::string text;
  for (const auto& [message, who] : messages) text += (text.empty() ? "" : "; ") + who + ": " + message;
  return text;
}

std::string format_number(double v) {
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, r.ptr);
}


Context::Context(Config config, std::shared_ptr<RankGroup> group)
    : m_config(std::move(config)), m_group(std::move(group)), m_decisions(m_group), m_trigger(m_config.trigger),
      m_field_labels(field_labels(m_config)) {
  // From here on config().backend names the renderer that runs: cpu or gpu.
  m_cpu_fallback = m_config.backend == Backend::automatic;
  check_config_rules(m_config);
  if (m_group->size() > 1) check_rank_rules(m_config);
  // Image-space occlusion is evaluated along every ray, by the CPU ray caster.
  if (m_config.lighting && m_config.lighting->occlusion_model &&
      m_config.lighting->occlusion.space == OcclusionSpace::image)
    m_config.backend = Backend::cpu;
  m_config.backend = resolve_backend(m_config.backend);
  // The log first: a log that cannot be opened leaves no database behind to refuse a retry.
  if (m_group->rank() == 0 && (!m_config.progress.log.empty() || m_config.progress.stderr_every > 0))
    m_progress = std::make_unique<ProgressLog>(m_config.progress);
  if (m_group->rank() == 0) m_writer = std::make_unique<ImageWriter>(m_config);
  if (m_config.store) {
    m_store = std::make_unique<FieldStore>(*m_config.store, m_group->rank(), m_group->size());
    if (m_group->rank() == 0 && !m_config.text.empty())
      write_file_atomic(m_config.store->directory + "/config.json", m_config.text, "store");
  }
}

Context::~Context() = default;

void Context::require_open(const char* call) const {
  if (m_finalized)
    throw Error(ErrorCode::invalid_operation, std::string(call) + ": the context was finalized; only pnb_destroy is allowed");
}

std::size_t Context::held_field_bytes() const {
  std::size_t n = 0;
  for (const auto& [name, f] : m_fields) n += f.owned.size();
  return n;
}

void Context::publish_mesh(const MeshView& mesh) {
  require_open("pnb_publish_mesh");
  MeshUpdate update;
  agreed("pnb_publish_mesh", [&] { update = plan_mesh_update(mesh); });
  // Every rank takes part below when any rank's mesh changed: the ranks share one frame and one
  // set of cameras, both from the union of their bounds.
  double unchanged = update.kind == MeshUpdate::Kind::same ? 1 : 0;
  m_group->minimum(&unchanged, 1);
  if (unchanged == 1) return;
  if (!update.tets) update.tets = *m_mesh->tets;  // this rank's points stayed; the shared frame may not
  const Bounds global = global_bounds(*m_group, update.tets->bounds);
  if (global.empty()) throw Error(ErrorCode::invalid_argument, "pnb_publish_mesh: no rank published a cell");
  update.tets->frame = LocalFrame::of(global);
  const bool new_segment = store_segment_everywhere(update.kind == MeshUpdate::Kind::fresh);
  agreed("pnb_publish_mesh", [&] { apply_mesh_update(mesh, std::move(update), global, new_segment); });
}

bool Context::store_segment_everywhere(bool fresh_here) {
  if (!m_store || m_group->size() == 1) return false;
  // min(not fresh) = 0 when some rank's topology is new; -max(segment) = min(-segment).
  double v[2] = {fresh_here ? 0.0 : 1.0, -static_cast<double>(m_store->last_segment())};
  m_group->minimum(v, 2);
  m_store->continue_after(static_cast<int>(-v[1]));
  return v[0] == 0;
}

namespace {

// The tets of the cells this rank renders: all, or those that are not ghosts (the ghosts still
// count for the cell fields' averages at the points, so the whole mesh is validated).
render::TetMesh prepare_own_cells(const MeshView& mesh) {
  if (mesh.point_count() == 0) {  // a part with no cell: nothing to prepare, nothing drawn
    render::TetMesh none;
    none.topology_version = mesh.topology_version;
    return none;
  }
  if (!mesh.ghost_cells) return render::prepare_tet_mesh(mesh, "pnb_publish_mesh");
  validate_mesh(mesh, "pnb_publish_mesh");
  const OwnCells own = without_ghosts(mesh);
  require(own.types.size() > 0, "pnb_publish_mesh: every cell is a ghost; a rank publishes at least one cell of its own");
  return render::prepare_tet_mesh(own.view, "pnb_publish_mesh (the cells that are not ghosts)");
}

}  // namespace

void Context::require_cells_or_allowed_none(const MeshView& mesh) const {
  if (mesh.point_count() > 0) return;
  const std::string none = "pnb_publish_mesh: this part has no cell (point_count, connectivity_count and cell_types_count 0)";
  require(m_group->size() > 1, none + "; a part without cells is for one rank of a run over several ranks");
}

Context::MeshUpdate Context::plan_mesh_update(const MeshView& mesh) const {
  using Kind = MeshUpdate::Kind;
  require_cells_or_allowed_none(mesh);
  if (!m_mesh || m_mesh->view.topology_version != mesh.topology_version) return {Kind::fresh, prepare_own_cells(mesh)};
  // Same topology. Counts are compared because they cost nothing and catch a solver that changed
  // its mesh but forgot to bump the version.
  require(mesh.point_count() == m_mesh->view.point_count() && mesh.cell_count() == m_mesh->view.cell_count(),
          "pnb_publish_mesh: topology_version " + std::to_string(mesh.topology_version) +
              " is unchanged but the mesh now has " + std::to_string(mesh.point_count()) + " points and " +
              std::to_string(mesh.cell_count()) + " cells (was " + std::to_string(m_mesh->view.point_count()) + " and " +
              std::to_string(m_mesh->view.cell_count()) + "); bump topology_version when the connectivity changes");
  if (!points_moved(mesh)) return {Kind::same, std::nullopt};
  if (!render::keeps_welds(*m_mesh->tets, mesh)) {
    log_line("pnb_publish_mesh: points that coincided when the mesh was prepared moved apart, which changes its "
             "adjacency: the mesh is prepared anew");
    return {Kind::fresh, prepare_own_cells(mesh)};
  }
  return {Kind::moved, render::move_tet_mesh(*m_mesh->tets, mesh, "pnb_publish_mesh")};
}

void Context::apply_mesh_update(const MeshView& mesh, MeshUpdate update, const Bounds& global, bool new_segment) {
  auto tets = std::make_shared<const render::TetMesh>(std::move(*update.tets));
  if (update.kind != MeshUpdate::Kind::same) log_if_tangled(*tets);
  if (update.kind == MeshUpdate::Kind::fresh) {
    prepare_mesh(mesh, std::move(tets));
  } else {
    move_geometry(std::move(tets));
    if (update.kind == MeshUpdate::Kind::moved) {
      ++m_geometry_updates;
      if (m_store) m_store->points_moved();
    }
    // Another rank's topology is new: every rank's part begins the next segment with it.
    if (new_segment) m_store->begin_segment(mesh.ghost_cells ? without_ghosts(mesh).view : m_mesh->view);
  }
  m_mesh->global_bounds = global;
  m_mesh->cameras = view_cameras(m_config, global);
}

void Context::prepare_mesh(const MeshView& mesh, std::shared_ptr<const render::TetMesh> tets) {
  auto p = std::make_unique<PreparedMesh>();
  p->tets = std::move(tets);
  p->renderer = make_renderer(p->tets);
  p->on_gpu = std::string(p->renderer->backend()) == "gpu";

  const std::size_t isz = scalar_size(mesh.connectivity.type);
  const auto* cb = static_cast<const std::byte*>(mesh.connectivity.data);
  p->connectivity.assign(cb, cb + mesh.connectivity.count * isz);
  if (mesh.offsets.count > 0) {
    const auto* ob = static_cast<const std::byte*>(mesh.offsets.data);
    p->offsets.assign(ob, ob + mesh.offsets.count * scalar_size(mesh.offsets.type));
  }
  p->cell_types.assign(mesh.cell_types, mesh.cell_types + mesh.cell_type_count);
  p->view = mesh;
  p->view.ghost_cells = nullptr;  // the prepared tets hold this rank's own cells already
  p->view.axes = {};  // the prepared copy is interleaved
  p->view.point_type = ScalarType::float64;
  p->view.connectivity.data = p->connectivity.data();
  p->view.offsets.data = p->offsets.empty() ? nullptr : p->offsets.data();
  p->view.cell_types = p->cell_types.data();
  m_mesh = std::move(p);
  point_view_at_tets();
  m_topology = m_mesh->view;
  m_topology.points.data = nullptr;  // the counts and the connectivity only: the points move
  ++m_preparations;
  // The store keeps this rank's own cells: a ghost is another rank's to keep.
  if (m_store) m_store->begin_segment(mesh.ghost_cells ? without_ghosts(mesh).view : m_mesh->view);
  // Fields were sized for the old mesh.
  m_fields.clear();
}

void Context::move_geometry(std::shared_ptr<const render::TetMesh> tets) {
  PreparedMesh& p = *m_mesh;
  p.renderer->move_points(tets);
  if (m_group->size() > 1) {
    // Level 0 spans the ranks' bounds, which move with the points: the volumes are made again.
    p.light_volumes.clear();
    p.shared_points.reset();
    p.scattering.reset();
  }
  for (auto& lv : p.light_volumes)
    if (lv) lv->move_points(tets);
  p.occlusions.clear();  // made again for the moved mesh at the next step
  p.tets = std::move(tets);
  point_view_at_tets();
}

void Context::log_if_tangled(const render::TetMesh& tets) const {
  if (!tets.tangled()) return;
  char text[256];
  std::snprintf(text, sizeof text,
                "pnb_publish_mesh: the mesh is tangled: its cells' volume (%.6g) differs from the volume its boundary "
                "encloses (%.6g), so cells overlap and pictures through the overlaps are undefined",
                tets.tet_volume, tets.enclosed_volume);
  log_line(text);
}

void Context::point_view_at_tets() {
  PreparedMesh& p = *m_mesh;
  p.view.points = {reinterpret_cast<const std::byte*>(p.tets->points.data()), p.tets->points.size(), sizeof(Vec3d)};
}

bool Context::points_moved(const MeshView& mesh) const {
  // One pass over the coordinates against the prepared copy: far cheaper than any update, so
  // that a solver may republish an unchanged mesh every step.
  const std::vector<Vec3d>& held = m_mesh->tets->points;
  for (std::size_t i = 0; i < mesh.point_count(); ++i)
    if (!(mesh.point(i) == held[i])) return true;
  return false;
}

MeshView Context::moved_view(const std::vector<Vec3d>& points) const {
  MeshView v = m_mesh->view;
  v.points = {reinterpret_cast<const std::byte*>(points.data()), points.size(), sizeof(Vec3d)};
  return v;
}

std::shared_ptr<const render::TetMesh> Context::prepared_tets() const {
  return m_mesh ? m_mesh->tets : nullptr;
}

FieldView packed_copy(const FieldView& field, std::vector<std::byte>& bytes) {
  const std::size_t item = scalar_size(field.type) * static_cast<std::size_t>(field.components);
  bytes.resize(item * field.values.count);
  // A packed array (the usual case) is one copy; a strided one, a copy per value.
  if (field.values.stride_bytes == static_cast<std::ptrdiff_t>(item) && !bytes.empty())
    std::memcpy(bytes.data(), field.values.data, bytes.size());
  else
    for (std::size_t i = 0; i < field.values.count; ++i) std::memcpy(&bytes[i * item], field.values.at(i), item);
  FieldView copy = field;
  copy.values = {bytes.data(), field.values.count, static_cast<std::ptrdiff_t>(item)};
  return copy;
}

void Context::publish_field(const FieldView& field, bool copy) {
  if (!check_field(field)) return;
  HeldField held;
  held.view = copy ? packed_copy(field, held.owned) : field;
  m_fields[field.name] = std::move(held);
}

bool Context::check_field(const FieldView& field) const {
  require_open("pnb_publish_field");
  if (!m_config.uses_field(field.name)) return false;
  const std::string who = "pnb_publish_field: field '" + field.name + "'";
  if (!m_mesh)
    throw Error(ErrorCode::invalid_operation, who + ": no mesh published yet; call pnb_publish_mesh first");
  require(field.type == ScalarType::float32 || field.type == ScalarType::float64, who + ": type must be float32 or float64");
  require(field.components >= 1, who + ": components must be >= 1, got " + std::to_string(field.components));
  const std::size_t expected =
      field.association == Association::point ? m_topology.point_count() : m_topology.cell_count();
  require(field.values.count == expected,
          who + " has " + std::to_string(field.values.count) + " values but the mesh has " + std::to_string(expected) +
              (field.association == Association::point ? " points" : " cells"));
  require(field.values.count == 0 || field.values.data != nullptr, who + ": values pointer is null");
  const std::size_t item = scalar_size(field.type) * static_cast<std::size_t>(field.components);
  require(field.values.stride_bytes >= static_cast<std::ptrdiff_t>(item),
          who + ": stride_bytes " + std::to_string(field.values.stride_bytes) + " is smaller than one item (" +
              std::to_string(item) + " bytes)");
  for (const auto& f : m_config.fields)
    require(f.name != field.name || f.mode == ComponentMode::magnitude || f.component < field.components,
            who + " has " + std::to_string(field.components) + " components but the config renders component " +
                std::to_string(f.component));
  return true;
}

void Context::drop_borrowed_fields() {
  for (auto it = m_fields.begin(); it != m_fields.end();)
    it = it->second.owned.empty() ? m_fields.erase(it) : std::next(it);
}

void Context::StepFailures::add(const Error& e) {
  text += (text.empty() ? "" : "; ") + std::string(e.what());
  if (code == ErrorCode::ok) code = e.code();
}

void Context::StepFailures::rethrow() const {
  if (code != ErrorCode::ok) throw Error(code, text);
}

Context::StepField& Context::gather_field(std::size_t index, std::int64_t cycle, StepValues& values) const {
  auto& v = values[index];
  if (v) return *v;
  const FieldConfig& f = m_config.fields[index];
  auto it = m_fields.find(f.name);
  if (it == m_fields.end())
    throw Error(ErrorCode::invalid_operation, "pnb_execute: field '" + f.name + "' was not published for cycle " +
                                                  std::to_string(cycle) + " (call pnb_publish_field before pnb_execute)");
  // A held view stays valid: borrowed views are dropped after every execute, copied ones own their data.
  StepField& step = v.emplace();
  step.values = point_values(m_mesh->view, it->second.view, f.mode, f.component);
  std::tie(step.lo, step.hi) = local_range(f, step.values);
  return step;
}

void Context::normalize_field(std::size_t index, StepField& step) const {
  if (!step.normalized.empty()) return;
  // The ranks' values share one range, so that a value has one colour on every rank.
  if (!m_config.fields[index].range) global_range(*m_group, step.lo, step.hi);
  std::tie(step.lo, step.hi) = usable_range(step.lo, step.hi);
  step.normalized = normalize_values(step.values, step.lo, step.hi);
}

std::unique_ptr<render::Renderer> Context::make_renderer(const std::shared_ptr<const render::TetMesh>& tets) const {
  if (m_config.backend == Backend::gpu) {
    try {
      return std::make_unique<render::GpuRayCaster>(process_gpu_device(false), tets);
    } catch (const Error& e) {
      if (!m_cpu_fallback || e.code() != ErrorCode::out_of_memory) throw;
      log_line(std::string("backend \"auto\": ") + e.what() + "; rendering this mesh on the CPU");
    }
  }
  return std::make_unique<render::CpuRayCaster>(tets);
}

render::OcclusionLighting& Context::occlusion_of(std::size_t index) {
  auto& occ = m_mesh->occlusions;
  if (occ.size() < m_config.fields.size()) occ.resize(m_config.fields.size());
  if (!occ[index]) {
    render::OcclusionSettings settings = m_config.lighting->occlusion;
    // Over several ranks, the extinction grid spans them all, so that their grids merge.
    if (m_group->size() > 1) settings.grid_bounds = m_mesh->global_bounds;
    // Cones are traced on the GPU when it renders.
    occ[index] = std::make_unique<render::OcclusionLighting>(m_mesh->tets, settings, m_config.lighting->lights,
                                                             m_mesh->on_gpu ? process_gpu_device(false) : nullptr);
  }
  return *occ[index];
}

render::LightVolume& Context::light_volume_of(std::size_t index) {
  auto& volumes = m_mesh->light_volumes;
  if (volumes.size() < m_config.fields.size()) volumes.resize(m_config.fields.size());
  auto& lv = volumes[index];
  // A plan that coarsens level 0, or brings it back, makes the volume again at that resolution.
  const int level0_wanted = m_plan && m_plan->degradation.level0_resolution > 0 ? m_plan->degradation.level0_resolution
                                                                                : m_config.lighting->level0_resolution;
  if (lv && lv->options().level0_resolution != level0_wanted) lv.reset();
  if (!lv) {
    const LightingConfig& l = *m_config.lighting;
    render::LightVolumeOptions lo;
    lo.level0_resolution = level0_wanted;
    lo.sigma_a = l.absorption;
    lo.sigma_s = l.scattering;
    // With the gpu backend the light is solved on the same device as the rendering.
    if (m_mesh->on_gpu) lo.device = process_gpu_device(false);
    // Over several ranks, level 0 spans them all, so that their grids merge (rank_lighting.h).
    // Over several ranks the scattering runs after the shared points are settled (RankScattering).
    if (m_group->size() > 1) {
      lo.level0_bounds = m_mesh->global_bounds;
      lo.sigma_s = {0, 0, 0};
    }
    lv = std::make_unique<render::LightVolume>(m_mesh->tets, lo);
    lv->set_lights(l.lights);
  }
  return *lv;
}

render::RenderOptions Context::prepare_lighting(std::size_t index, const StepField& step, const render::TransferFunction& tf) {
  render::RenderOptions options;
  if (!lit(m_config)) return options;
  const LightingConfig& l = *m_config.lighting;
  const std::vector<float>* light_rgb = nullptr;
  const auto t0 = Clock::now();
  if (l.occlusion_model) {
    prepare_occlusion(index, step, tf);
  } else if (l.model == render::LightingModel::light_volume) {
    light_rgb = &solve_light_volume(index, step, tf);
  }
  m_last_step.light_ms += ms_since(t0);
  options.shading = shading_of(l, light_rgb);
  return options;
}

// Each collective step runs between agreed phases, which every rank passes or none does.
void Context::prepare_occlusion(std::size_t index, const StepField& step, const render::TransferFunction& tf) {
  render::OcclusionLighting* occ = nullptr;
  agreed("pnb_execute", [&] {
    occ = &occlusion_of(index);
    occ->resample_field(step.normalized, tf);
  });
  if (m_group->size() > 1) {
    occ->combine_extinction(extinction_merge(*m_group));
    exchange_shadow_gaps(*occ);
  }
  agreed("pnb_execute", [&] { occ->finish_field(); });
}

void Context::exchange_shadow_gaps(render::OcclusionLighting& occ) {
  const Bounds& b = m_mesh->tets->bounds;
  const std::vector<double> boxes = m_group->all_gather({b.lo.x, b.lo.y, b.lo.z, b.hi.x, b.hi.y, b.hi.z});
  std::vector<render::GapSegment> open;
  GapRoutes routes;
  agreed("pnb_execute", [&] {
    open = occ.open_gaps();
    routes = route_gaps(*m_group, boxes, open);
  });
  const auto asked = m_group->exchange(routes.requests);
  std::vector<std::vector<double>> answers;
  agreed("pnb_execute", [&] { answers = answer_gaps(occ, asked); });
  const auto answered = m_group->exchange(answers);
  agreed("pnb_execute", [&] { occ.add_gap_depths(sum_gap_answers(routes, answered, open.size())); });
}

const std::vector<float>& Context::solve_light_volume(std::size_t index, const StepField& step,
                                                      const render::TransferFunction& tf) {
  render::LightVolume* lv = nullptr;
  agreed("pnb_execute", [&] {
    lv = &light_volume_of(index);
    lv->set_field(step.normalized, tf);
  });
  if (m_group->size() > 1) lv->combine_level0(level0_merge(*m_group));
  agreed("pnb_execute", [&] { m_last_step.light = lv->update(light_budget()); });
  note_light_update(index);
  return m_group->size() > 1 ? settle_shared_points(index, *lv) : lv->light_rgb();
}

const std::vector<float>& Context::settle_shared_points(std::size_t index, const render::LightVolume& lv) {
  PreparedMesh& p = *m_mesh;
  if (!p.shared_points) p.shared_points = std::make_unique<SharedPoints>(*m_group, *p.tets, m_config.lighting->lights);
  if (p.settled_light.size() < m_config.fields.size()) p.settled_light.resize(m_config.fields.size());
  std::vector<float>& rgb = p.settled_light[index];
  SharedPoints::Rho rho;
  std::vector<std::vector<double>> to_each;
  agreed("pnb_execute", [&] {
    for (std::size_t k = 0; k < m_config.lighting->lights.size(); ++k) rho.push_back(&lv.light_rho(k));
    to_each = p.shared_points->messages(*m_group, rho);
    rgb = lv.light_rgb();
  });
  const auto from_each = m_group->exchange(to_each);
  agreed("pnb_execute", [&] { p.shared_points->settle(*m_group, from_each, rho, rgb); });
  return scatter_over_ranks(index, rgb);
}

const std::vector<float>& Context::scatter_over_ranks(std::size_t index, const std::vector<float>& source) {
  const LightingConfig& l = *m_config.lighting;
  if (!(l.scattering[0] > 0 || l.scattering[1] > 0 || l.scattering[2] > 0)) return source;
  PreparedMesh& p = *m_mesh;
  const auto t0 = Clock::now();
  if (!p.scattering) p.scattering = std::make_unique<RankScattering>(*m_group, *p.tets, *p.shared_points);
  if (p.scattered_light.size() < m_config.fields.size()) p.scattered_light.resize(m_config.fields.size());
  const render::LightVolumeOptions defaults;
  const RankScattering::Report r = p.scattering->solve(*m_group, source, l.scattering, defaults.scatter_tolerance,
                                                       defaults.scatter_max_iterations, p.scattered_light[index]);
  m_last_step.light.scatter_iterations += r.iterations;
  m_last_step.light.l1_scatter_ms += ms_since(t0);
  if (!r.converged) m_last_step.light.converged = false;
  return p.scattered_light[index];
}

std::vector<RenderedView> Context::render_views(std::size_t index, const StepField& step, const render::TransferFunction& tf,
                                                render::RenderOptions options, double& render_ms) {
  const bool occlusion = lit(m_config) && m_config.lighting->occlusion_model;
  std::vector<RenderedView> views;
  for (const std::size_t c : m_cameras_now) {
    const render::Camera camera = step_camera(c);
    // Occlusion looks towards the viewer: one light field per camera (or, in image space, a
    // light evaluated along every ray).
    if (occlusion) {
      render::OcclusionLighting& occ = *m_mesh->occlusions[index];
      if (m_config.lighting->occlusion.space == OcclusionSpace::image) {
        options.shading.light_at = occ.light_at(camera.eye);
      } else {
        const auto t_occ = Clock::now();
        options.shading.light_rgb = &occ.light_rgb(camera.eye);
        m_last_step.light_ms += ms_since(t_occ);
      }
    }
    RenderedView& view = views.emplace_back();
    view.field = index;
    view.camera = c;
    const auto t0 = Clock::now();
    options.ray_runs = m_group->size() > 1;  // the ranks' runs are merged by composite()
    options.ray_runs_memory_bytes = m_config.runs_memory_bytes;
    m_mesh->renderer->render(step.normalized, tf, camera, options, view.output);
    render_ms += ms_since(t0);
    ++m_last_step.views;
    m_last_step.rendered_pixels += static_cast<double>(camera.width) * camera.height;
  }
  return views;
}

ImageLabels Context::labels_of(const ComposedImage& image, double time, std::int64_t cycle) const {
  const ViewCamera& cam = m_mesh->cameras[image.camera];
  char cycle_text[32];
  std::snprintf(cycle_text, sizeof cycle_text, "c%06lld_", static_cast<long long>(cycle));
  ImageLabels l;
  l.time = format_number(time);
  l.phi = cam.phi;
  l.theta = cam.theta;
  l.camera = cam.name;
  l.field = m_field_labels[image.field];
  if (m_config.lighting) l.lighting = lighting_label(*m_config.lighting);
  l.stem = cycle_text + cam.stem;
  if (m_plan) {
    Degradation d = m_plan->degradation;
    d.light = m_light_short.size() > image.field && m_light_short[image.field];
    l.degraded = d.text();
  } else if (m_config.budget) {
    l.degraded = "none";
  }
  return l;
}

void Context::render_field(std::size_t index, double time, std::int64_t cycle, StepValues& values,
                           std::vector<CinemaDatabase::Row>& rows, double& render_ms) {
  StepField* step = nullptr;
  const auto t_gather = Clock::now();
  agreed("pnb_execute", [&] { step = &gather_field(index, cycle, values); });  // gather
  normalize_field(index, *step);
  m_last_step.gather_ms += ms_since(t_gather);
  const FieldConfig& f = m_config.fields[index];
  const render::TransferFunction tf = resolve_transfer_function(f, step->lo, step->hi, m_mesh->global_bounds.diagonal());
  std::vector<RenderedView> views;
  const render::RenderOptions options = prepare_lighting(index, *step, tf);
  agreed("pnb_execute", [&] { views = render_views(index, *step, tf, options, render_ms); });
  for (RenderedView& view : views) {
    const auto t_composite = Clock::now();
    std::optional<ComposedImage> image = composite(std::move(view));
    if (image && m_plan && m_plan->degradation.image_scale < 1) image = enlarged(*image, m_config.width, m_config.height);
    const auto t_write = Clock::now();
    m_last_step.composite_ms += std::chrono::duration<double, std::milli>(t_write - t_composite).count();
    if (image && m_writer) rows.push_back(m_writer->write(*image, labels_of(*image, time, cycle)));
    m_last_step.write_ms += ms_since(t_write);
  }
}

std::optional<ComposedImage> Context::composite(RenderedView&& view) {
  if (m_group->size() == 1) return composite_view(std::move(view), m_config.background);
  // Every rank's runs of the view merged in depth order; the whole image on rank 0.
  RenderedView merged;
  merged.field = view.field;
  merged.camera = view.camera;
  merged.output.image = m_group->composite(view.output.runs, view.output.image.width, view.output.image.height);
  if (m_group->rank() != 0) return std::nullopt;
  return composite_view(std::move(merged), m_config.background);
}

bool Context::trigger_fires(double time, std::int64_t cycle) {
  if (m_decisions->size() == 1) return m_trigger.fires(time, cycle);
  // Asked first and recorded only once the ranks agree: a refused step leaves the time rule as it
  // was. min(not fires) = 0 when some rank fires; min(fires) = 0 when some rank does not; the
  // least and greatest time, and of each half of the cycle (exact in a double), differ when some
  // rank passed others.
  const bool fires = m_trigger.would_fire(time, cycle);
  const CycleHalves c = halves_of(cycle);
  double v[8] = {fires ? 0.0 : 1.0, fires ? 1.0 : 0.0, time, -time, c.high, -c.high, c.low, -c.low};
  m_decisions->minimum(v, 8);
  if (v[2] != -v[3] || v[4] != -v[5] || v[6] != -v[7])
    throw Error(ErrorCode::invalid_argument, step_disagreement(*m_decisions, time, cycle));
  if (v[0] == 0 && v[1] == 0)
    throw Error(ErrorCode::invalid_operation, "pnb_execute: the ranks disagree whether cycle " + std::to_string(cycle) +
                                                  " renders: every rank must pass the same time and cycle");
  return m_trigger.fires(time, cycle);
}

bool Context::execute(double time, std::int64_t cycle) {
  struct DropBorrowed {
    Context* c;
    ~DropBorrowed() { c->drop_borrowed_fields(); }
  } drop{this};
  // The trigger's statistics read the published fields by name; without them nothing does.
  std::map<std::string, FieldView> published;
  if (!m_trigger.watched_fields().empty())
    for (const auto& [name, held] : m_fields) published.emplace(name, held.view);
  return accounted([&] { return run_step(time, cycle, decide_step(time, cycle, published)); });
}

void Context::account_execute(double inside_ms) {
  const auto now = Clock::now();
  m_last_return = now;
  if (m_config.trigger.max_share <= 0) return;
  // The clock starts as the first step returns: from then on the solver's own time is seen too.
  if (!m_first_execute) {
    m_first_execute = now;
    return;
  }
  m_inside_ms += inside_ms;
  const double wall = std::chrono::duration<double, std::milli>(now - *m_first_execute).count();
  double share = wall > 0 ? m_inside_ms / wall : 0;
  // The largest share over the ranks, so that every rank leaves out the same steps.
  if (m_decisions->size() > 1) {
    double negative = -share;
    m_decisions->minimum(&negative, 1);
    share = -negative;
  }
  m_share = share;
  m_trigger.observe_share(share);
}

StepDecision Context::decide_step(double time, std::int64_t cycle, const std::map<std::string, FieldView>& fields) {
  require_open("pnb_execute");
  agreed_on(*m_decisions, "pnb_execute", [&] {
    if (!m_mesh) throw Error(ErrorCode::invalid_operation, "pnb_execute: no mesh published; call pnb_publish_mesh first");
    require(std::isfinite(time), "pnb_execute: time must be finite");
  });
  if (m_last_return) {
    // The solver's own time since the last step returned: what a share budget is a share of.
    m_solver_step_ms.push_back(ms_since(*m_last_return));
    if (m_solver_step_ms.size() > 5) m_solver_step_ms.erase(m_solver_step_ms.begin());
  }
  StepDecision d;
  d.renders = trigger_fires(time, cycle);
  d.budget_ms = budget_for_step(d.renders);
  StepFailures failures;
  observe_trigger_statistics(cycle, fields, failures);
  d.failure = failures.text;
  d.code = failures.code;
  return d;
}

bool Context::run_step(double time, std::int64_t cycle, const StepDecision& decision) {
  require_open("pnb_execute");
  StepFailures failures;
  failures.text = decision.failure;
  failures.code = decision.code;
  StepValues values(m_config.fields.size());
  const auto t0 = Clock::now();
  // The history is kept on its own cadence, whether or not this step renders.
  if (m_store && m_store->records(cycle)) store_fields(time, cycle, values, failures);
  const double store_ms = ms_since(t0);
  if (!decision.renders) {
    report(failures);
    return false;
  }

  std::vector<CinemaDatabase::Row> rows;
  double render_ms = 0;
  const std::uint64_t bytes_before = m_writer ? m_writer->bytes_written() : 0;
  m_plan = plan_this_step(decision.budget_ms);
  m_cameras_now = step_cameras();
  m_light_short.assign(m_config.fields.size(), false);
  m_last_step = {};
  m_last_step.store_ms = store_ms;
  m_last_step.budget_ms = decision.budget_ms;
  for (std::size_t i = 0; i < m_config.fields.size(); ++i) {
    try {
      render_field(i, time, cycle, values, rows, render_ms);
    } catch (const Error& e) {
      // One field failing must not cost the others their images.
      failures.add(e);
    }
  }
  // Only images that were completely written are listed.
  if (m_writer) {
    const auto t_commit = Clock::now();
    try {
      m_writer->commit(rows);
    } catch (const Error& e) {
      failures.add(e);
    }
    m_last_step.write_ms += ms_since(t_commit);
  }
  StepStats& s = m_last_step;
  s.cycle = cycle;
  s.images = static_cast<int>(rows.size());
  s.render_ms = render_ms;
  s.total_ms = ms_since(t0);
  s.other_ms = std::max(0.0, s.total_ms - (s.store_ms + s.gather_ms + s.light_ms + s.render_ms + s.composite_ms + s.write_ms));
  s.degradation = step_degradation();
  log_progress(time, bytes_before, failures);
  s.status = failures.code;
  report(failures, &s.status);
  return true;
}

void Context::log_progress(double time, std::uint64_t bytes_before, StepFailures& failures) {
  if (!m_progress) return;
  StepReport r;
  r.time = time;
  r.stats = &m_last_step;
  r.fields = m_field_labels;
  r.bytes_written = m_writer ? m_writer->bytes_written() - bytes_before : 0;
  r.failure = failures.text;
  try {
    m_progress->step(r);
  } catch (const Error& e) {
    failures.add(e);
  }
}

void Context::observe_trigger_statistics(std::int64_t cycle, const std::map<std::string, FieldView>& fields,
                                         StepFailures& failures) {
  const std::vector<std::string>& names = m_trigger.watched_fields();
  if (names.empty()) return;
  // Per field: min, -max (both reduced by minimum), then the finite values' sum and count.
  std::vector<double> extremes, sums;
  bool published = true;
  try {
    for (const std::string& name : names) {
      const auto it = fields.find(name);
      if (it == fields.end())
        throw Error(ErrorCode::invalid_operation, "pnb_execute: trigger.when reads field '" + name +
                                                      "', which was not published for cycle " + std::to_string(cycle) +
                                                      " (pnb_step_needs lists it at every step)");
      const std::vector<double> v = point_values(m_topology, it->second, ComponentMode::magnitude, 0);
      const ValueRange r = finite_range(v);
      double sum = 0;
      for (double x : v)
        if (std::isfinite(x)) sum += x;
      extremes.insert(extremes.end(), {r.finite_count ? r.lo : HUGE_VAL, r.finite_count ? -r.hi : HUGE_VAL});
      sums.insert(sums.end(), {sum, static_cast<double>(r.finite_count)});
    }
  } catch (const Error& e) {
    failures.add(e);
    published = false;
  }
  // Every rank takes part in the reductions; a rank that lacks a field makes every rank skip
  // this step's statistics, so that all keep the same ones.
  double ok = published ? 1 : 0;
  m_decisions->minimum(&ok, 1);
  if (ok == 0) return;
  m_decisions->minimum(extremes.data(), static_cast<int>(extremes.size()));
  const std::vector<double> all = m_decisions->all_gather(sums);
  StatsByField stats;
  for (std::size_t i = 0; i < names.size(); ++i) {
    double sum = 0, count = 0;
    for (std::size_t at = 2 * i; at < all.size(); at += sums.size()) sum += all[at], count += all[at + 1];
    if (count == 0) continue;  // no finite value anywhere: its comparisons are false
    stats[names[i]] = {extremes[2 * i], -extremes[2 * i + 1], sum / count};
  }
  m_trigger.observe(std::move(stats));
}

bool Context::on_any_rank(bool mine) {
  double none = mine ? 0 : 1;
  m_decisions->minimum(&none, 1);
  return none == 0;
}

StepNeeds Context::step_needs(double time, std::int64_t cycle) const {
  require_open("pnb_step_needs");
  StepNeeds needs;
  needs.renders = m_trigger.would_fire(time, cycle);
  needs.stores = m_store && m_store->records(cycle);
  needs.mesh = !m_mesh;
  auto need = [&needs](const std::string& name) {
    if (std::find(needs.fields.begin(), needs.fields.end(), name) == needs.fields.end()) needs.fields.push_back(name);
  };
  if (needs.renders || needs.stores)
    for (const FieldConfig& f : m_config.fields) need(f.name);
  // The trigger's statistics are taken at every step.
  for (const std::string& name : m_trigger.watched_fields()) need(name);
  return needs;
}

void Context::report(const StepFailures& failures, ErrorCode* status) {
  if (m_group->size() == 1) return failures.rethrow();
  // A failure on one rank alone (a write on rank 0) is every rank's status.
  const auto failed = m_group->failures(static_cast<int>(failures.code), failures.text);
  if (failed.empty()) return;
  const auto code = static_cast<ErrorCode>(failed.front().code);
  if (status) *status = code;
  throw Error(code, ranks_text(failed, m_group->size()));
}

void Context::store_fields(double time, std::int64_t cycle, StepValues& values, StepFailures& failures) {
  if (m_store->points_move()) {
    try {
      m_store->record_points(time, cycle, m_mesh->tets->points, render::smallest_altitude(*m_mesh->tets));
    } catch (const Error& e) {
      failures.add(e);
    }
  }
  for (std::size_t i = 0; i < m_config.fields.size(); ++i) {
    if (m_fields.find(m_config.fields[i].name) == m_fields.end()) continue;  // reported when the step renders
    try {
      m_store->record(m_field_labels[i], time, cycle, gather_field(i, cycle, values).values);
    } catch (const Error& e) {
      failures.add(e);
    }
  }
}

void Context::finalize() {
  // Every rendered step is committed when execute() returns; the store still holds its last,
  // partial window.
  m_finalized = true;
  m_fields.clear();
  if (m_store) m_store->finish();
}

}  // namespace penumbra::insitu

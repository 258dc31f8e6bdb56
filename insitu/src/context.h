// SPDX-License-Identifier: BSD-3-Clause
// insitu/src/context.h -- the in-situ runtime behind the C API
#pragma once
#include <chrono>
#include <cstdint>
#include <exception>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "cinema_database.h"
#include "config.h"
#include "image_writer.h"
#include "penumbra/core/elapsed.h"
#include "penumbra/core/error.h"
#include "penumbra/core/field_view.h"
#include "penumbra/core/mesh_view.h"
#include "penumbra/render/light_volume.h"
#include "penumbra/render/occlusion.h"
#include "penumbra/render/renderer.h"
#include "penumbra/render/tet_mesh.h"
#include "rank_group.h"
#include "step_stages.h"
#include "trigger.h"

namespace penumbra::insitu {

class FieldStore;
class ProgressLog;

/// What the last rendering step did, for diagnostics and examples.
struct StepStats {
  std::int64_t cycle = 0;
  int images = 0;
  double render_ms = 0;  ///< ray casting only
  double total_ms = 0;   ///< field conversion, rendering, PNG encoding and database commit
  /// Light volume (lighting model light-volume): time spent and the last field's solve report,
  /// whose residual tells how far the light is from converged.
  double light_ms = 0;
  render::LightUpdateReport light;
  /// The other stages of total_ms: the store's record of the step, the fields gathered and
  /// normalised, the views composited, the PNGs and data.csv written; other_ms is the rest.
  double store_ms = 0, gather_ms = 0, composite_ms = 0, write_ms = 0, other_ms = 0;
  /// "budget": this step's (0: none), and what the step gave up for it.
  double budget_ms = 0;
  Degradation degradation;
  /// What the next step's plan measures by: views rendered and their pixels, the largest light
  /// piece (one light's level-0 solve) and whether every field's light converged.
  int views = 0;
  double rendered_pixels = 0;
  double light_piece_ms = 0;
  bool light_converged = true;
  /// The step's own outcome: ok, or the code of the error its execute threw (over ranks, the
  /// agreed one; asynchronously, the next call's).
  ErrorCode status = ErrorCode::ok;
};

/// The first half of a step, decided where the solver calls (Context::decide_step): whether it
/// renders, and the failure of taking the trigger's statistics (reported with the step).
struct StepDecision {
  bool renders = false;
  double budget_ms = 0;  ///< "budget": the step's time, the same on every rank; 0 = none
  std::string failure;
  ErrorCode code = ErrorCode::ok;
};

/// `field`'s values packed into `bytes` (its buffer reused), and the view of that copy.
FieldView packed_copy(const FieldView& field, std::vector<std::byte>& bytes);

/// What execute(time, cycle) would read, decided as execute() decides.
struct StepNeeds {
  bool renders = false;  ///< the trigger fires
  bool stores = false;   ///< the store records the step
  bool mesh = false;     ///< no mesh is prepared yet: execute() fails without one
  /// Names execute() reads: the rendered ones when it renders or stores, the trigger's always.
  std::vector<std::string> fields;
};

/// One solver's in-situ pipeline: holds the prepared mesh, the fields published since the last
/// step, the trigger and the Cinema database. Not thread-safe. Every method throws
/// penumbra::Error on bad input or failed I/O; the C API turns that into a status.
class Context {
public:
  /// Opens the output database (see CinemaDatabase; on rank 0 of `group` only) and checks the
  /// backend. With a group of several ranks (an MPI run), publish_mesh, execute and finalize are
  /// collective: every rank calls them, in the same order; a failure on any rank is every rank's
  /// Error, naming the rank, and no rank is left waiting.
  explicit Context(Config config, std::shared_ptr<RankGroup> group = serial_group());
  ~Context();
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;

  /// Prepares `mesh` for rendering (validated, split into tets, adjacency, ray caster) and keeps
  /// an owned copy of its topology for cell-to-point averaging; `mesh` may be freed afterwards.
  /// Under the topology_version already prepared, the point and cell counts must be the same and
  /// the points are compared with the prepared ones (one pass): unchanged, nothing is redone;
  /// moved, only what depends on the positions is (move_tet_mesh, Renderer::move_points). The
  /// cameras and the float32 frame come from the union of the ranks' bounds.
  void publish_mesh(const MeshView& mesh);

  /// Hands in a field for the next execute(). Fields the config does not render are ignored:
  /// neither checked nor copied. Borrowed fields (copy = false) are read during the next
  /// execute() and forgotten after it; copied fields are copied now and kept until replaced or
  /// until the topology changes.
  void publish_field(const FieldView& field, bool copy);

  /// Renders every configured field from every camera if the trigger fires, writes the images
  /// and commits them to the database. Returns whether the step rendered. A field that cannot
  /// be rendered (e.g. not published) is skipped, the others are still written, and then an
  /// Error naming every failure is thrown.
  bool execute(double time, std::int64_t cycle);

  /// execute() in two halves, for a runner that takes the second to another thread
  /// (AsyncRunner): decide_step records the trigger's decision and takes its statistics from
  /// `fields` (the step's published fields by name), touching nothing that run_step touches
  /// besides reading the prepared mesh; run_step records the step in the store and, when the
  /// decision renders, renders, writes and commits it from the fields published to this context.
  StepDecision decide_step(double time, std::int64_t cycle, const std::map<std::string, FieldView>& fields);
  bool run_step(double time, std::int64_t cycle, const StepDecision& decision);

  /// Time the solver spent inside one pnb_execute, for the adaptive cadence ("trigger":
  /// {"max_share"}): the share of its wall time since the first step returned, over ranks the
  /// largest (collective when max_share is set). execute() accounts its own; an asynchronous
  /// runner its.
  void account_execute(double inside_ms);
  /// Runs one pnb_execute's `step` (returning whether it renders) and accounts the solver's time
  /// inside it, whether it returns or throws.
  template <class Step>
  bool accounted(Step&& step) {
    const auto t0 = std::chrono::steady_clock::now();
    bool rendered = false;
    try {
      rendered = step();
    } catch (...) {
      account_execute(ms_since(t0));
      throw;
    }
    account_execute(ms_since(t0));
    return rendered;
  }
  /// The last share account_execute found (0 without max_share).
  double execute_share() const { return m_share; }

  /// Over several ranks, decide_step and account_execute talk through a group of their own from
  /// here on (collective), so that they may run on the solver's thread while run_step talks
  /// through the context's group on a worker's.
  void decide_on_own_group() { m_decisions = m_group->duplicate(); }
  /// Runs `check` (a collective call's reading of its arguments, on the calling thread) and
  /// agrees on it through the decisions' group, as a step's phases agree: when it threw on any
  /// rank, every rank throws one Error naming each such rank, so that none goes on into the
  /// call's collectives alone. A finalized context (finalized alike on every rank) refuses first,
  /// with no collective.
  void agree_arguments(const char* call, const std::function<void()>& check) {
    require_open(call);
    agreed_on(*m_decisions, call, check);
  }
  /// Whether `mine` holds on any rank, through the decisions' group (collective): an
  /// asynchronous run skips a step on every rank when any rank's worker is still busy.
  bool on_any_rank(bool mine);
  /// The ranks' group (serial: one rank).
  const RankGroup& ranks() const { return *m_group; }
  /// The prepared mesh (over the context's own copies of its connectivity) at `points`, for
  /// publish_mesh: the same topology moved. Needs a prepared mesh.
  MeshView moved_view(const std::vector<Vec3d>& points) const;
  /// The prepared tet mesh (null before the first mesh): immutable, so another thread may read it.
  std::shared_ptr<const render::TetMesh> prepared_tets() const;
  /// The prepared mesh's cell count, from the topology the solver's thread may read while a
  /// worker moves the points.
  std::size_t prepared_cell_count() const { return m_topology.cell_count(); }

  /// publish_field's checks alone, storing nothing: false for a field the config does not use,
  /// Error for one it refuses.
  bool check_field(const FieldView& field) const;
  /// Forgets the fields published with copy = false (execute() does so after every step).
  void drop_borrowed_fields();

  /// What execute(time, cycle) would need, recording nothing: this rank's trigger and store
  /// cadence (every rank that passes the same time and cycle gets the same answer).
  StepNeeds step_needs(double time, std::int64_t cycle) const;

  /// Ends the run; later calls other than destruction throw Error(invalid_operation).
  void finalize();
  bool finalized() const { return m_finalized; }

  const Config& config() const { return m_config; }
  const StepStats& last_step() const { return m_last_step; }
  /// Number of times a mesh was actually prepared (republishing an unchanged topology does not count).
  std::size_t mesh_preparations() const { return m_preparations; }
  /// Number of times moved points were taken under an unchanged topology (move_points).
  std::size_t geometry_updates() const { return m_geometry_updates; }
  /// Fields currently held, and the bytes of field values copied into the context.
  std::size_t held_field_count() const { return m_fields.size(); }
  std::size_t held_field_bytes() const;

private:
  struct PreparedMesh;
  struct HeldField {
    FieldView view;
    std::vector<std::byte> owned;  ///< packed copy when published with copy = true
  };

  /// Errors of one step's fields, gathered so that a failing field costs the others nothing.
  struct StepFailures {
    std::string text;
    ErrorCode code = ErrorCode::ok;
    void add(const Error& e);
    void rethrow() const;
  };
  /// One config field's point values for this step, converted once for the store and the images:
  /// in double as published, and mapped from [lo, hi] to [0, 1] in double before narrowing to
  /// float, which is what the renderers see (the transfer function is mapped alike), so that a
  /// field of any magnitude and offset keeps its variation.
  struct StepField {
    std::vector<double> values;
    double lo = 0, hi = 1;
    std::vector<float> normalized;
  };
  using StepValues = std::vector<std::optional<StepField>>;

  void require_open(const char* call) const;
  /// Runs `phase` (this rank's own work, no collective inside), then agrees with the other ranks:
  /// when any rank's phase threw, every rank throws one Error naming each failing rank and its
  /// message. A serial run rethrows its own exception as it is.
  template <class Phase>
  void agreed(const char* call, Phase&& phase) {
    agreed_on(*m_group, call, std::forward<Phase>(phase));
  }
  /// The same over `group`: the decisions' group for what decide_step runs.
  template <class Phase>
  void agreed_on(RankGroup& group, const char* call, Phase&& phase);
  /// A part with no cell is one rank's of a run over several ranks; in one process it throws
  /// Error(invalid_argument) saying so.
  void require_cells_or_allowed_none(const MeshView& mesh) const;
  /// This rank's part of a publish: what changed, and the tet mesh for it in its own frame.
  struct MeshUpdate {
    enum class Kind { same, moved, fresh } kind = Kind::same;
    std::optional<render::TetMesh> tets;
  };
  MeshUpdate plan_mesh_update(const MeshView& mesh) const;
  /// Takes `update` (its frame set from the ranks' `global` bounds): a new preparation, or the
  /// geometry moved; the cameras from `global`.
  void apply_mesh_update(const MeshView& mesh, MeshUpdate update, const Bounds& global, bool new_segment);
  /// Over several ranks with a store: whether every rank begins a new segment with this mesh
  /// (some rank's topology is new), and the segment numbers agreed (collective).
  bool store_segment_everywhere(bool fresh_here);
  /// A new topology: the renderer, the owned connectivity; a new store segment; fields dropped.
  void prepare_mesh(const MeshView& mesh, std::shared_ptr<const render::TetMesh> tets);
  /// The same topology at other positions (or in another frame): the renderer and the light
  /// volumes move their geometry, occlusion is made again.
  void move_geometry(std::shared_ptr<const render::TetMesh> tets);
  /// Whether any point of `mesh` differs from the prepared mesh's.
  bool points_moved(const MeshView& mesh) const;
  /// The prepared view's points, at the prepared tet mesh's.
  void point_view_at_tets();
  void log_if_tangled(const render::TetMesh& tets) const;
  /// Whether the step renders, the same on every rank (Error when the ranks disagree).
  bool trigger_fires(double time, std::int64_t cycle);
  /// The rendered step in the progress log (rank 0): a log that cannot be written is one of the
  /// step's failures.
  void log_progress(double time, std::uint64_t bytes_before, StepFailures& failures);
  /// The statistics of the fields the trigger's `when` reads, taken at every step for the next
  /// steps' decisions (collective: reduced over the ranks). A field not published is a failure.
  void observe_trigger_statistics(std::int64_t cycle, const std::map<std::string, FieldView>& fields,
                                  StepFailures& failures);
  /// "budget": the step's time (the least over ranks: collective when the step renders with a
  /// share budget), from the solver's recent time per step.
  double budget_for_step(bool renders);
  /// "budget": what this rendering step gives up (nothing on the first, which measures), planned
  /// from the last rendering step's costs, the largest over ranks (collective).
  std::optional<StepPlan> plan_this_step(double budget_ms);
  /// The cameras this step renders: all of them, or with a plan that leaves some out, the next
  /// ones in turn.
  std::vector<std::size_t> step_cameras();
  /// The lighting budget of a field's light volume this step: lighting.budget within the plan's.
  render::LightBudget light_budget() const;
  /// After field `index`'s light update: its largest piece and whether it converged (over ranks,
  /// whether it did on every rank), and whether it fell short of the plan's allowance.
  void note_light_update(std::size_t index);
  /// The plan's degradation with the light's part as it turned out.
  Degradation step_degradation() const;
  /// The step's failures: thrown, on every rank when any rank had one; the agreed code also into
  /// `status` when given.
  void report(const StepFailures& failures, ErrorCode* status = nullptr);
  /// The composite stage: a view's image over the background; with several ranks their runs
  /// merged first. Empty on ranks other than 0 (rank 0 writes the database).
  std::optional<ComposedImage> composite(RenderedView&& view);
  /// Point values of config field `index` this step, and this rank's range of them; throws
  /// Error(invalid_operation) when the field was not published.
  StepField& gather_field(std::size_t index, std::int64_t cycle, StepValues& values) const;
  /// The ranks' common range of the field (collective), and its values mapped by it.
  void normalize_field(std::size_t index, StepField& step) const;
  /// The renderer of a newly published mesh: the config's backend (the CPU where "auto" finds
  /// that the GPU cannot hold the mesh).
  std::unique_ptr<render::Renderer> make_renderer(const std::shared_ptr<const render::TetMesh>& tets) const;
  /// Field `index`'s lighting state, made at its first step and kept across steps.
  render::OcclusionLighting& occlusion_of(std::size_t index);
  render::LightVolume& light_volume_of(std::size_t index);
  /// Prepare stage: the field's lighting for this step (light volume updated within its budget,
  /// occlusion volume set), as the options every camera renders with.
  render::RenderOptions prepare_lighting(std::size_t index, const StepField& step, const render::TransferFunction& tf);
  /// The field's occlusion volume set for this step (over several ranks, the extinction grid
  /// merged across them).
  void prepare_occlusion(std::size_t index, const StepField& step, const render::TransferFunction& tf);
  /// Over several ranks: the shadow gaps that leave this rank's cells integrated through the
  /// others' (collective; rank_lighting.h).
  void exchange_shadow_gaps(render::OcclusionLighting& occ);
  /// The field's light volume updated for this step (over several ranks, level 0 merged across
  /// them first): its light per point.
  const std::vector<float>& solve_light_volume(std::size_t index, const StepField& step, const render::TransferFunction& tf);
  /// The light with the points shared with other ranks settled (collective; SharedPoints).
  const std::vector<float>& settle_shared_points(std::size_t index, const render::LightVolume& lv);
  /// Over several ranks with scattering: `source` scattered over every rank's points
  /// (collective; RankScattering), else `source`.
  const std::vector<float>& scatter_over_ranks(std::size_t index, const std::vector<float>& source);
  /// Render stage: the field from every camera.
  std::vector<RenderedView> render_views(std::size_t index, const StepField& step, const render::TransferFunction& tf,
                                         render::RenderOptions options, double& render_ms);
  /// A view's camera as this step renders it: smaller by the plan's image scale.
  render::Camera step_camera(std::size_t camera) const;
  /// The database values of a composed image of this step.
  ImageLabels labels_of(const ComposedImage& image, double time, std::int64_t cycle) const;
  /// One field through the stages after gathering: prepare, render, composite, write.
  void render_field(std::size_t index, double time, std::int64_t cycle, StepValues& values,
                    std::vector<CinemaDatabase::Row>& rows, double& render_ms);
  void store_fields(double time, std::int64_t cycle, StepValues& values, StepFailures& failures);

  Config m_config;
  std::shared_ptr<RankGroup> m_group;
  std::shared_ptr<RankGroup> m_decisions;  ///< decide_step's: m_group, or its duplicate (decide_on_own_group)
  Trigger m_trigger;
  std::unique_ptr<ImageWriter> m_writer;  ///< the write stage; opened with the context, on rank 0 only
  std::unique_ptr<FieldStore> m_store;  ///< null without a "store" config
  std::unique_ptr<ProgressLog> m_progress;  ///< "progress", on rank 0; null without one
  bool m_cpu_fallback = false;           ///< "auto": a mesh the GPU cannot hold renders on the CPU
  std::unique_ptr<PreparedMesh> m_mesh;
  std::map<std::string, HeldField> m_fields;
  /// The prepared mesh's counts and connectivity, without its points: what the step's decision
  /// and the fields' checks read, left alone when the points move (on an asynchronous worker).
  MeshView m_topology;
  std::vector<std::string> m_field_labels;  ///< value of the `field` column per config entry
  StepStats m_last_step;
  std::optional<std::chrono::steady_clock::time_point> m_first_execute;  ///< the adaptive cadence's start
  double m_inside_ms = 0, m_share = 0;
  /// "budget": when pnb_execute last returned, the solver's last times per step since, this
  /// step's plan, the next camera in turn and, per field, whether its light fell short of it.
  std::optional<std::chrono::steady_clock::time_point> m_last_return;
  std::vector<double> m_solver_step_ms;
  std::optional<StepPlan> m_plan;
  std::size_t m_next_camera = 0;
  std::vector<std::size_t> m_cameras_now;
  std::vector<bool> m_light_short;
  std::size_t m_preparations = 0;
  std::size_t m_geometry_updates = 0;
  bool m_finalized = false;
};

/// Formats a number for data.csv: shortest text that reads back to the same double.
std::string format_number(double v);

/// Several ranks' failures as one message: each distinct message once, after the ranks that had
/// it; a message every rank had, alone.
std::string ranks_text(const std::vector<RankGroup::Failure>& failed, int ranks);

template <class Phase>
void Context::agreed_on(RankGroup& group, const char* call, Phase&& phase) {
  int code = 0;
  std::string message;
  std::exception_ptr mine;
  try {
    phase();
  } catch (const Error& e) {
    code = static_cast<int>(e.code());
    message = e.what();
    mine = std::current_exception();
  } catch (const std::exception& e) {
    code = static_cast<int>(ErrorCode::internal_error);
    message = std::string(call) + ": " + e.what();
    mine = std::current_exception();
  }
  if (group.size() == 1) {
    if (mine) std::rethrow_exception(mine);
    return;
  }
  const auto failed = group.failures(code, message);
  if (failed.empty()) return;
  throw Error(static_cast<ErrorCode>(code != 0 ? code : failed.front().code), ranks_text(failed, group.size()));
}

}  // namespace penumbra::insitu

// SPDX-License-Identifier: BSD-3-Clause
// insitu/src/context.h -- the in-situ runtime behind the C API
#pragma once
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "cinema_database.h"
#include "config.h"
#include "image_writer.h"
#include "penumbra/core/error.h"
#include "penumbra/core/field_view.h"
#include "penumbra/core/mesh_view.h"
#include "penumbra/render/light_volume.h"
#include "penumbra/render/occlusion.h"
#include "penumbra/render/renderer.h"
#include "step_stages.h"
#include "trigger.h"

namespace penumbra::insitu {

class FieldStore;

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
};

/// One solver's in-situ pipeline: holds the prepared mesh, the fields published since the last
/// step, the trigger and the Cinema database. Not thread-safe. Every method throws
/// penumbra::Error on bad input or failed I/O; the C API turns that into a status.
class Context {
public:
  /// Opens the output database (see CinemaDatabase) and checks the backend.
  explicit Context(Config config);
  ~Context();
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;

  /// Prepares `mesh` for rendering (validated, split into tets, adjacency, ray caster) and keeps
  /// an owned copy of its topology for cell-to-point averaging; `mesh` may be freed afterwards.
  /// Under the topology_version already prepared, the point and cell counts must be the same and
  /// the points are compared with the prepared ones (one pass): unchanged, nothing is redone;
  /// moved, only what depends on the positions is (move_points).
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
  /// A new topology: the mesh split, its adjacency, the renderer, cameras; a new store segment.
  void prepare_mesh(const MeshView& mesh);
  /// The same topology with its points moved: the connectivity's work is kept (move_tet_mesh),
  /// the renderer and light volumes move their geometry, occlusion is made again, the cameras
  /// follow the bounds and the store records the coordinates. A mesh whose welded points moved
  /// apart is prepared anew.
  void move_points(const MeshView& mesh);
  /// Whether any point of `mesh` differs from the prepared mesh's.
  bool points_moved(const MeshView& mesh) const;
  /// The prepared view's points and the cameras, from the prepared mesh.
  void place_views();
  void log_if_tangled(const render::TetMesh& tets) const;
  /// Point values of config field `index` this step; throws Error(invalid_operation) when the
  /// field was not published.
  const StepField& field_values(std::size_t index, std::int64_t cycle, StepValues& values) const;
  /// The renderer of a newly published mesh: the config's backend (the CPU where "auto" finds
  /// that the GPU cannot hold the mesh).
  std::unique_ptr<render::Renderer> make_renderer(const std::shared_ptr<const render::TetMesh>& tets) const;
  /// Field `index`'s lighting state, made at its first step and kept across steps.
  render::OcclusionLighting& occlusion_of(std::size_t index);
  render::LightVolume& light_volume_of(std::size_t index);
  /// Prepare stage: the field's lighting for this step (light volume updated within its budget,
  /// occlusion volume set), as the options every camera renders with.
  render::RenderOptions prepare_lighting(std::size_t index, const StepField& step, const render::TransferFunction& tf);
  /// Render stage: the field from every camera.
  std::vector<RenderedView> render_views(std::size_t index, const StepField& step, const render::TransferFunction& tf,
                                         render::RenderOptions options, double& render_ms);
  /// The database values of a composed image of this step.
  ImageLabels labels_of(const ComposedImage& image, double time, std::int64_t cycle) const;
  /// One field through the stages after gathering: prepare, render, composite, write.
  void render_field(std::size_t index, double time, std::int64_t cycle, StepValues& values,
                    std::vector<CinemaDatabase::Row>& rows, double& render_ms);
  void drop_borrowed_fields();
  void store_fields(double time, std::int64_t cycle, StepValues& values, StepFailures& failures);

  Config m_config;
  Trigger m_trigger;
  std::unique_ptr<ImageWriter> m_writer;  ///< the write stage; opened with the context
  std::unique_ptr<FieldStore> m_store;  ///< null without a "store" config
  bool m_cpu_fallback = false;           ///< "auto": a mesh the GPU cannot hold renders on the CPU
  std::unique_ptr<PreparedMesh> m_mesh;
  std::map<std::string, HeldField> m_fields;
  std::vector<std::string> m_field_labels;  ///< value of the `field` column per config entry
  StepStats m_last_step;
  std::size_t m_preparations = 0;
  std::size_t m_geometry_updates = 0;
  bool m_finalized = false;
};

/// Formats a number for data.csv: shortest text that reads back to the same double.
std::string format_number(double v);

}  // namespace penumbra::insitu

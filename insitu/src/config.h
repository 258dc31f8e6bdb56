// SPDX-License-Identifier: BSD-3-Clause
// insitu/src/config.h -- the runtime's JSON configuration, parsed and checked
#pragma once
#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "penumbra/compression/codec_params.h"
#include "penumbra/core/field_view.h"
#include "penumbra/core/vec3.h"
#include "penumbra/render/light_volume.h"
#include "penumbra/render/occlusion.h"
#include "penumbra/render/shading.h"
#include "penumbra/render/transfer_function.h"
#include "step_budget.h"
#include "trigger_expression.h"

namespace penumbra::insitu {

/// What pnb_create does when the output directory already exists and is not empty.
enum class IfExists { error, resume };

/// Which renderer runs the steps. `automatic` takes a hardware GPU when EGL lists one and the
/// CPU path otherwise; `gpu` also runs on a software device (llvmpipe) and says so once in the
/// log. A Context replaces `automatic` by the backend it resolved to.
enum class Backend { cpu, gpu, automatic };

/// An explicit camera: eye looking at target.
struct LookAtCamera {
  std::string name;
  Vec3d eye, target, up{0, 0, 1};
  double fov_y_deg = 30.0;
};

/// Cinema orbit cameras: every (phi, theta) pair, in degrees (see render::Camera::orbit).
struct OrbitCameras {
  std::vector<double> phi;
  std::vector<double> theta;
  double fov_y_deg = 30.0;
};

/// How transfer-function x values are read.
enum class XUnits { normalized, data };
/// How opacity control values are read: extinction per world length unit, or per bounding-box
/// diagonal of the mesh (a = 1 gives optical depth 1 across the whole diagonal).
enum class OpacityUnit { world, diagonal };

/// One rendered field.
struct FieldConfig {
  std::string name;  ///< matched against published field names, whatever their association
  ComponentMode mode = ComponentMode::magnitude;
  int component = 0;
  std::optional<std::pair<double, double>> range;  ///< nullopt = "auto" (finite range per step)
  XUnits x_units = XUnits::normalized;
  OpacityUnit opacity_unit = OpacityUnit::diagonal;
  render::TransferFunction transfer_function;  ///< x in x_units, opacity in opacity_unit
};

/// When a step renders: every `every_cycles` cycles, every `every_time` of simulation time, and/or
/// when the fields' statistics satisfy `when` (trigger_expression.h).
struct TriggerConfig {
  std::int64_t every_cycles = 0;  ///< 0 = not used
  double every_time = 0.0;        ///< 0 = not used
  std::optional<TriggerExpression> when;
  /// Adaptive cadence: a step the rules above render is left out while the solver's time inside
  /// pnb_execute exceeds this share of its wall time since the first step; 0 = not used.
  double max_share = 0.0;
};

/// Cone-traced directional occlusion and shadows (insitu/README.md, "lighting.occlusion").
using OcclusionConfig = render::OcclusionSettings;
using render::OcclusionSpace;

/// How rendered samples are lit (insitu/README.md, "lighting").
struct LightingConfig {
  /// "occlusion" maps to LightingModel::light_volume with the light field from cone tracing.
  bool occlusion_model = false;
  OcclusionConfig occlusion;
  render::LightingModel model = render::LightingModel::none;
  /// Light sources: the light volume's, and the first directional one is Phong's key light
  /// (none: a headlight).
  std::vector<render::Light> lights;
  double absorption = 1.0;                    ///< sigma_a~ of the light volume
  std::array<double, 3> scattering{0, 0, 0};  ///< sigma_s~ per channel
  int level0_resolution = 128;
  double ambient = 0.35, diffuse = 0.55, specular = 0.25, shininess = 24.0;
  /// Light-volume work per rendered step (the light converges over steps when it runs out).
  render::LightBudget budget;
};

/// The run's compressed field history (insitu/README.md, "store").
/// How a store keeps the coordinates of a mesh whose points move (coordinate_store.h).
struct CoordinateStoreConfig {
  bool lossless = false;  ///< every step's coordinates exactly, in float64
  /// Else compressed, every point within this fraction of the thinnest cell's altitude.
  double altitude_fraction = 1.0 / 64;
};

struct StoreConfig {
  std::string directory;
  CoordinateStoreConfig coordinates;
  std::int64_t every_cycles = 1;  ///< record the rendered fields at every Nth cycle
  compression::CodecParams codec;
  std::uint64_t memory_budget_bytes = 0;  ///< 0: what two windows of every field need
};

/// What a run reports of its rendered steps (insitu/README.md, "progress").
struct ProgressConfig {
  std::string log;       ///< one JSON line per rendered step appended to this file; empty: none
  int stderr_every = 0;  ///< a short line on stderr every Nth rendered step; 0: never
};

/// "async": steps rendered on a worker thread while the solver goes on (async_runner.h).
struct AsyncConfig {
  bool enabled = false;
  /// A step that renders or stores while the worker is still busy: the solver waits for it
  /// (false), or the step is skipped and counted (true).
  bool skip_when_busy = false;
};

/// The whole configuration. See insitu/README.md for the JSON schema.
struct Config {
  std::string output_directory;
  IfExists if_exists = IfExists::error;
  int width = 256;
  int height = 256;
  float background[3] = {1.0f, 1.0f, 1.0f};
  std::optional<OrbitCameras> orbit;
  std::vector<LookAtCamera> look_at;
  std::vector<FieldConfig> fields;
  TriggerConfig trigger;
  Backend backend = Backend::cpu;
  /// Present when the config has a "lighting" object: the database then gets a lighting column.
  std::optional<LightingConfig> lighting;
  std::optional<StoreConfig> store;
  /// "compositing": {"runs_memory_mb"}: over several ranks, the most one rank's ray runs of one
  /// view may take (RenderOptions::ray_runs_memory_bytes); a view that needs more fails on every
  /// rank, naming the rank.
  std::size_t runs_memory_bytes = std::size_t{2} << 30;
  ProgressConfig progress;
  AsyncConfig async;
  /// "budget": a rendering step's most time, and what it gives up to keep to it (step_budget.h);
  /// the database then gets a `degraded` column.
  std::optional<BudgetConfig> budget;
  /// The JSON text parse_config read: a store keeps it as config.json, so that views of the run
  /// can be rendered again later with the same fields, transfer functions and lighting.
  std::string text;

  /// True when `name` is rendered by at least one field entry or read by the trigger.
  bool uses_field(const std::string& name) const;
};

/// Parses `text_or_path`: JSON text when its first non-blank character is '{', else a file path.
/// Throws Error(invalid_argument) naming the key path ("config: fields[0].range must be ...")
/// for unknown keys, wrong types or values, and Error(io_error) when the file cannot be read.
Config parse_config(const std::string& text_or_path);

/// The rules that join several keys, checked by a Context before it opens anything (and by
/// pnb_check_config): lighting.occlusion.space "image" is evaluated by the CPU ray caster only,
/// so it throws Error(backend_unavailable) with backend "gpu".
void check_config_rules(const Config& config);

}  // namespace penumbra::insitu

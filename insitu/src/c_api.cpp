// SPDX-License-Identifier: BSD-3-Clause
// insitu/src/c_api.cpp -- the C API: argument checks, conversion to views, and the guard that
// keeps every exception out of the host program
#include <cstddef>
#include <cstdio>
#include <cstring>
#include <mutex>
#include <new>
#include <string>
#include <vector>

#include "config.h"
#include "c_api_internal.h"
#include "async_runner.h"
#include "context.h"
#include "penumbra/core/error.h"
#include "penumbra/penumbra.h"
#include "sized_structs.h"

struct pnb_context_s {
  std::unique_ptr<penumbra::insitu::Context> context;    ///< null when `async` holds it
  std::unique_ptr<penumbra::insitu::AsyncRunner> async;  ///< "async": the steps on a worker thread
  std::string last_error;
  std::vector<std::string> needed_fields;  ///< of the last pnb_step_needs
};

namespace {

// The sizes of the first layouts with struct_size (ABI 2), padding included: the smallest struct
// a caller may pass. A member added later starts at or after these sizes (never in the padding,
// which an older caller leaves unset); these constants then keep the ABI-2 sizes.
constexpr std::size_t kFirstMeshDescBytes = offsetof(pnb_mesh_desc, point_x);  // ABI 3 added the three arrays
constexpr std::size_t kFirstFieldDescBytes = sizeof(pnb_field_desc);
constexpr std::size_t kFirstStepStatsBytes = offsetof(pnb_step_stats, store_ms);  // ABI 5 added the stages
constexpr std::size_t kFirstNeedsBytes = sizeof(pnb_needs);

using penumbra::Error;
using penumbra::ErrorCode;

/// Last failure of a call without a usable context (pnb_create, or a NULL ctx); per thread so
/// that concurrent contexts on different threads do not mix messages.
thread_local std::string t_last_error;

pnb_status record(pnb_context ctx, pnb_status status, const char* message) noexcept {
  try {
    (ctx ? ctx->last_error : t_last_error) = message;
  } catch (...) {
    // Out of memory while storing the message: the status still tells what happened.
  }
  return status;
}

template <class Body>
pnb_status guarded(pnb_context ctx, Body&& body) noexcept {
  try {
    body();
    return PNB_OK;
  } catch (const Error& e) {
    return record(ctx, static_cast<pnb_status>(e.code()), e.what());
  } catch (const std::bad_alloc&) {
    return record(ctx, PNB_OUT_OF_MEMORY, "out of memory");
  } catch (const std::exception& e) {
    return record(ctx, PNB_INTERNAL_ERROR, e.what());
  } catch (...) {
    return record(ctx, PNB_INTERNAL_ERROR, "unknown exception");
  }
}

/// Every call but pnb_create needs a live context; a NULL one is reported per thread.
pnb_status null_context(const char* call) noexcept {
  return record(nullptr, PNB_INVALID_ARGUMENT, (std::string(call) + ": ctx is NULL").c_str());
}

/// The integer a C caller stored in an enum field. C allows any int there, but in C++ reading an
/// out-of-range value through the enum type is undefined, so the bytes are read as an int.
template <class Enum>
int raw(const Enum& e) {
  static_assert(sizeof(Enum) == sizeof(int), "C enums are int-sized");
  int v;
  std::memcpy(&v, &e, sizeof v);
  return v;
}

penumbra::ScalarType scalar_type(const pnb_type& t) { return static_cast<penumbra::ScalarType>(raw(t)); }

bool is_float(const pnb_type& t) { return raw(t) == PNB_FLOAT32 || raw(t) == PNB_FLOAT64; }
bool is_index(const pnb_type& t) { return raw(t) == PNB_INT32 || raw(t) == PNB_INT64; }
bool valid_ownership(const pnb_ownership& o) { return raw(o) == PNB_BORROW || raw(o) == PNB_COPY; }

/// The stride of items of `item` bytes given as `given` (0: packed); throws naming `name` when
/// it is shorter than an item.
std::ptrdiff_t item_stride(std::int64_t given, std::int64_t item, const std::string& name, const std::string& what) {
  const std::int64_t stride = given == 0 ? item : given;
  penumbra::require(stride >= item, name + " " + std::to_string(given) + " is smaller than " + what + " (" +
                                        std::to_string(item) + " bytes)");
  return static_cast<std::ptrdiff_t>(stride);
}

/// The mesh's points into `v`: interleaved xyz, or three coordinate arrays (points NULL).
void set_points(const pnb_mesh_desc& d, const std::string& who, penumbra::MeshView& v) {
  using penumbra::require;
  const bool any_array = d.point_x || d.point_y || d.point_z;
  require(d.points != nullptr || any_array, who + "points is NULL (and no point_x, point_y, point_z either)");
  require(d.points == nullptr || !any_array,
          who + "give the points either interleaved (points) or as three arrays (point_x, point_y, point_z), not both");
  const std::size_t n = static_cast<std::size_t>(d.point_count);
  const auto size = static_cast<std::int64_t>(penumbra::scalar_size(scalar_type(d.point_type)));
  if (d.points) {
    v.points = {static_cast<const std::byte*>(d.points), n,
                item_stride(d.point_stride_bytes, 3 * size, who + "point_stride_bytes", "one xyz point")};
    return;
  }
  require(d.point_x && d.point_y && d.point_z, who + "point_x, point_y and point_z go together: one of them is NULL");
  const std::ptrdiff_t stride = item_stride(d.point_axis_stride_bytes, size, who + "point_axis_stride_bytes", "one coordinate");
  const void* axes[3] = {d.point_x, d.point_y, d.point_z};
  for (int a = 0; a < 3; ++a) v.axes[a] = {static_cast<const std::byte*>(axes[a]), n, stride};
  v.points = {nullptr, n, 0};
}

/// Checks what can be checked without reading the arrays, then wraps them in a MeshView.
/// validate_mesh (inside preparation) checks their contents.
penumbra::MeshView mesh_view(const pnb_mesh_desc& d) {
  using penumbra::require;
  const std::string who = "pnb_publish_mesh: ";
  require(is_float(d.point_type), who + "point_type must be PNB_FLOAT32 or PNB_FLOAT64, got " + std::to_string(raw(d.point_type)));
  require(is_index(d.index_type), who + "index_type must be PNB_INT32 or PNB_INT64, got " + std::to_string(raw(d.index_type)));
  penumbra::MeshView v;
  v.topology_version = d.topology_version;
  // No point, no cell: a rank that holds none of the rendered region (the context decides whether
  // its run allows one).
  if (d.point_count == 0 && d.connectivity_count == 0 && d.cell_types_count == 0) return v;
  require(d.point_count > 0, who + "point_count must be > 0, got " + std::to_string(d.point_count));
  set_points(d, who, v);
  require(d.connectivity_count > 0, who + "connectivity_count must be > 0, got " + std::to_string(d.connectivity_count));
  require(d.connectivity != nullptr, who + "connectivity is NULL");
  require(d.cell_types != nullptr, who + "cell_types is NULL");
  require(d.cell_types_count >= 1, who + "cell_types_count must be >= 1, got " + std::to_string(d.cell_types_count));

  v.point_type = scalar_type(d.point_type);
  v.connectivity = {d.connectivity, static_cast<std::size_t>(d.connectivity_count), scalar_type(d.index_type)};
  v.cell_types = d.cell_types;
  v.cell_type_count = static_cast<std::size_t>(d.cell_types_count);
  v.topology_version = d.topology_version;
  v.ghost_cells = d.cell_ghosts;
  if (d.offsets) {
    std::size_t cells = v.cell_type_count;
    if (cells == 1) {
      const int n = penumbra::cell_point_count(d.cell_types[0]);
      require(n > 0, who + "unsupported cell type " + std::to_string(d.cell_types[0]) +
                         " (expected 10 tetra, 12 hexahedron, 13 wedge or 14 pyramid)");
      cells = v.connectivity.count / static_cast<std::size_t>(n);
    }
    v.offsets = {d.offsets, cells + 1, scalar_type(d.index_type)};
  } else {
    require(v.cell_type_count == 1, who + "offsets is NULL but cell_types_count is " + std::to_string(d.cell_types_count) +
                                        " (offsets may be NULL only when every cell has one type: cell_types_count 1)");
  }
  return v;
}

penumbra::FieldView field_view(const pnb_field_desc& d) {
  using penumbra::require;
  const std::string who = "pnb_publish_field: ";
  require(d.name != nullptr, who + "name is NULL");
  penumbra::FieldView f;
  f.name = d.name;
  require(raw(d.association) == PNB_POINT_FIELD || raw(d.association) == PNB_CELL_FIELD,
          who + "field '" + f.name + "': association must be PNB_POINT_FIELD or PNB_CELL_FIELD");
  require(is_float(d.type), who + "field '" + f.name + "': type must be PNB_FLOAT32 or PNB_FLOAT64");
  require(d.components >= 1, who + "field '" + f.name + "': components must be >= 1, got " + std::to_string(d.components));
  require(d.count >= 0, who + "field '" + f.name + "': count must be >= 0, got " + std::to_string(d.count));
  const std::int64_t item = d.components * static_cast<std::int64_t>(penumbra::scalar_size(scalar_type(d.type)));
  f.association = raw(d.association) == PNB_POINT_FIELD ? penumbra::Association::point : penumbra::Association::cell;
  f.type = scalar_type(d.type);
  f.components = d.components;
  f.values = {static_cast<const std::byte*>(d.values), static_cast<std::size_t>(d.count),
              static_cast<std::ptrdiff_t>(d.stride_bytes == 0 ? item : d.stride_bytes)};
  return f;
}

}  // namespace

namespace {

/// `call` on what runs the context's steps: its asynchronous runner, or the context itself (both
/// offer the same calls).
template <class Call>
decltype(auto) on_runner(pnb_context ctx, Call&& call) {
  return ctx->async ? call(*ctx->async) : call(*ctx->context);
}

}  // namespace

namespace penumbra::insitu {

namespace {

/// Whether "async" can run over `group`: its worker talks to the other ranks from a thread of its
/// own, which MPI allows at MPI_THREAD_MULTIPLE. Below it every step runs inside pnb_execute,
/// where the solver's thread does the communication, and rank 0 says so once per process.
bool may_run_async(const RankGroup& group) {
  const std::string refused = group.threads_refused();
  if (refused.empty()) return true;
  static std::once_flag said;
  if (group.rank() == 0)
    std::call_once(said, [&refused] {
      std::fprintf(stderr,
                   "penumbra: \"async\" over MPI ranks needs MPI_THREAD_MULTIPLE, and MPI was initialised with %s: "
                   "every step runs inside pnb_execute instead\n",
                   refused.c_str());
    });
  return false;
}

}  // namespace

pnb_status create_context(const char* call, const char* config, std::shared_ptr<RankGroup> group, pnb_context* out) {
  if (out) *out = nullptr;
  std::unique_ptr<pnb_context_s> ctx;
  // Created on every rank, then agreed: a rank that failed (rank 0 alone opens the database)
  // makes every rank's creation fail, naming it.
  const pnb_status status = guarded(nullptr, [&] {
    require(out != nullptr, std::string(call) + ": out is NULL");
    require(config != nullptr, std::string(call) + ": config is NULL (expected a file path or JSON text)");
    ctx = std::make_unique<pnb_context_s>();
    ctx->context = std::make_unique<Context>(parse_config(config), group);
  });
  if (group->size() > 1) {
    const auto failed = group->failures(status == PNB_OK ? 0 : static_cast<int>(status), t_last_error);
    if (!failed.empty()) return record(nullptr, static_cast<pnb_status>(failed.front().code), ranks_text(failed, group->size()).c_str());
  }
  if (status != PNB_OK) return status;
  // Once every rank has its context: over ranks the runner's making is collective.
  const AsyncConfig& async = ctx->context->config().async;
  if (async.enabled && may_run_async(*group)) {
    const pnb_status started = guarded(nullptr, [&] { ctx->async = std::make_unique<AsyncRunner>(std::move(ctx->context), async.skip_when_busy); });
    // A runner that failed to start on one rank fails the creation on every rank.
    if (group->size() > 1) {
      const auto failed = group->failures(started == PNB_OK ? 0 : static_cast<int>(started), t_last_error);
      if (!failed.empty()) return record(nullptr, static_cast<pnb_status>(failed.front().code), ranks_text(failed, group->size()).c_str());
    }
    if (started != PNB_OK) return started;
  }
  *out = ctx.release();
  return status;
}

pnb_status creation_failed(pnb_status status, const std::string& message) { return record(nullptr, status, message.c_str()); }

}  // namespace penumbra::insitu

extern "C" {

pnb_status pnb_create(const char* config, pnb_context* out) {
  return penumbra::insitu::create_context("pnb_create", config, penumbra::insitu::serial_group(), out);
}

pnb_status pnb_check_config(const char* config) {
  return guarded(nullptr, [&] {
    penumbra::require(config != nullptr, "pnb_check_config: config is NULL (expected a file path or JSON text)");
    penumbra::insitu::check_config_rules(penumbra::insitu::parse_config(config));
  });
}

pnb_status pnb_publish_mesh(pnb_context ctx, const pnb_mesh_desc* mesh, pnb_ownership own) {
  if (!ctx) return null_context("pnb_publish_mesh");
  return guarded(ctx, [&] {
    on_runner(ctx, [&](auto& runner) {
      // Over ranks the call is collective: a descriptor refused on one rank is every rank's error.
      penumbra::MeshView view;
      runner.agree_arguments("pnb_publish_mesh", [&] {
        penumbra::require(mesh != nullptr, "pnb_publish_mesh: mesh is NULL");
        penumbra::require(valid_ownership(own), "pnb_publish_mesh: own must be PNB_BORROW or PNB_COPY");
        view = mesh_view(penumbra::insitu::read_sized(*mesh, pnb_mesh_desc PNB_MESH_DESC_INIT, kFirstMeshDescBytes,
                                                      "pnb_publish_mesh", "pnb_mesh_desc", "PNB_MESH_DESC_INIT"));
      });
      // Penumbra copies what it keeps of a mesh, so both ownership modes behave the same.
      runner.publish_mesh(view);
    });
  });
}

pnb_status pnb_publish_field(pnb_context ctx, const pnb_field_desc* field, pnb_ownership own) {
  if (!ctx) return null_context("pnb_publish_field");
  return guarded(ctx, [&] {
    penumbra::require(field != nullptr, "pnb_publish_field: field is NULL");
    penumbra::require(valid_ownership(own), "pnb_publish_field: own must be PNB_BORROW or PNB_COPY");
    const pnb_field_desc d = penumbra::insitu::read_sized(*field, pnb_field_desc PNB_FIELD_DESC_INIT, kFirstFieldDescBytes,
                                                          "pnb_publish_field", "pnb_field_desc", "PNB_FIELD_DESC_INIT");
    on_runner(ctx, [&](auto& runner) { runner.publish_field(field_view(d), raw(own) == PNB_COPY); });
  });
}

pnb_status pnb_execute(pnb_context ctx, double time, int64_t cycle) {
  if (!ctx) return null_context("pnb_execute");
  return guarded(ctx, [&] { on_runner(ctx, [&](auto& runner) { runner.execute(time, cycle); }); });
}

namespace {

int degradation_bits(const penumbra::insitu::Degradation& d) {
  return (d.light ? PNB_DEGRADED_LIGHT : 0) | (d.level0_resolution > 0 ? PNB_DEGRADED_LEVEL0 : 0) |
         (d.image_scale < 1 ? PNB_DEGRADED_IMAGE : 0) | (d.cameras_reduced() ? PNB_DEGRADED_CAMERAS : 0);
}

}  // namespace

pnb_status pnb_last_step(pnb_context ctx, pnb_step_stats* out) {
  if (!ctx) return null_context("pnb_last_step");
  return guarded(ctx, [&] {
    penumbra::require(out != nullptr, "pnb_last_step: out is NULL");
    const penumbra::insitu::StepStats s = on_runner(ctx, [](auto& runner) { return penumbra::insitu::StepStats(runner.last_step()); });
    pnb_step_stats stats PNB_STEP_STATS_INIT;
    stats.cycle = s.cycle;
    stats.images = s.images;
    stats.render_ms = s.render_ms;
    stats.total_ms = s.total_ms;
    stats.light_ms = s.light_ms;
    stats.light_residual = s.light.residual;
    stats.light_converged = s.light.converged ? 1 : 0;
    stats.store_ms = s.store_ms;
    stats.gather_ms = s.gather_ms;
    stats.composite_ms = s.composite_ms;
    stats.write_ms = s.write_ms;
    stats.other_ms = s.other_ms;
    stats.skipped_steps = ctx->async ? ctx->async->skipped_steps() : 0;
    stats.budget_ms = s.budget_ms;
    stats.image_scale = s.degradation.image_scale;
    stats.degraded = degradation_bits(s.degradation);
    stats.cameras_rendered = s.degradation.cameras;
    stats.level0_resolution = s.degradation.level0_resolution;
    stats.status = static_cast<pnb_status>(s.status);
    penumbra::insitu::write_sized(stats, out, kFirstStepStatsBytes, "pnb_last_step", "pnb_step_stats", "PNB_STEP_STATS_INIT");
  });
}

pnb_status pnb_step_needs(pnb_context ctx, double time, int64_t cycle, pnb_needs* out) {
  if (!ctx) return null_context("pnb_step_needs");
  return guarded(ctx, [&] {
    penumbra::require(out != nullptr, "pnb_step_needs: out is NULL");
    const penumbra::insitu::StepNeeds needs = on_runner(ctx, [&](auto& runner) { return runner.step_needs(time, cycle); });
    pnb_needs answer PNB_NEEDS_INIT;
    answer.renders = needs.renders ? 1 : 0;
    answer.stores = needs.stores ? 1 : 0;
    answer.needs_mesh = needs.mesh ? 1 : 0;
    answer.field_count = static_cast<int>(needs.fields.size());
    penumbra::insitu::write_sized(answer, out, kFirstNeedsBytes, "pnb_step_needs", "pnb_needs", "PNB_NEEDS_INIT");
    ctx->needed_fields = needs.fields;
  });
}

const char* pnb_needed_field(pnb_context ctx, int index) {
  if (!ctx || index < 0 || static_cast<std::size_t>(index) >= ctx->needed_fields.size()) return nullptr;
  return ctx->needed_fields[static_cast<std::size_t>(index)].c_str();
}

pnb_status pnb_finalize(pnb_context ctx) {
  if (!ctx) return null_context("pnb_finalize");
  return guarded(ctx, [&] { on_runner(ctx, [](auto& runner) { runner.finalize(); }); });
}

const char* pnb_last_error(pnb_context ctx) { return ctx ? ctx->last_error.c_str() : t_last_error.c_str(); }

void pnb_destroy(pnb_context ctx) {
  if (!ctx) return;
  guarded(ctx, [&] {
    on_runner(ctx, [](auto& runner) {
      if (!runner.finalized()) runner.finalize();
    });
  });
  delete ctx;
}

}  // extern "C"

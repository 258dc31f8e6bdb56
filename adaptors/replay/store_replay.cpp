// SPDX-License-Identifier: BSD-3-Clause
// adaptors/replay/store_replay.cpp -- stored mesh and fields -> C API, step by step
#include "store_replay.h"

#include <algorithm>
#include <filesystem>
#include <memory>
#include <ostream>
#include <vector>

#include "penumbra/core/error.h"
#include "penumbra/insitu/stored_run.h"
#include "penumbra/penumbra.h"
#include "step_range.h"

namespace penumbra::replay {
namespace {

// The first segment-NNN of a store directory, or `path` itself when it is a segment.
std::string segment_of(const std::string& path) {
  if (std::filesystem::exists(path + "/mesh.pnbm")) return path;
  std::vector<std::string> segments;
  for (const auto& e : std::filesystem::directory_iterator(path))
    if (e.path().filename().string().rfind("segment-", 0) == 0) segments.push_back(e.path().string());
  std::sort(segments.begin(), segments.end());
  if (segments.empty()) throw Error(ErrorCode::io_error, "'" + path + "' holds no stored segment");
  return segments.front();
}

}  // namespace

bool is_store(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_directory(path, ec)) return false;
  if (std::filesystem::exists(path + "/mesh.pnbm", ec)) return true;
  for (const auto& e : std::filesystem::directory_iterator(path, ec))
    if (e.path().filename().string().rfind("segment-", 0) == 0) return true;
  return false;
}

int replay_store(const std::string& config, const std::string& path, const std::string& steps, bool quiet,
                 std::ostream& out, std::ostream& err) {
  std::unique_ptr<insitu::StoredRun> run;
  try {
    run = insitu::StoredRun::open(segment_of(path));
  } catch (const Error& e) {
    err << "penumbra-replay: INPUT '" << path << "': " << e.what() << "\n";
    return 1;
  }
  const std::size_t n = run->step_count();
  const auto [first, last] = step_range(steps, n);
  if (!quiet)
    out << "penumbra-replay: stored run '" << path << "' (" << run->mesh().point_count() << " points, "
        << run->fields().size() << " field(s), " << n << " step(s)), replaying steps " << first << ".." << last - 1
        << "\n";
  run->start_at(first);  // the first pages load while the context and the mesh are set up
  pnb_context ctx = nullptr;
  if (pnb_create(config.c_str(), &ctx) != PNB_OK) {
    err << "penumbra-replay: " << pnb_last_error(nullptr) << "\n";
    return 1;
  }
  std::size_t failures = 0;
  auto fail = [&](const std::string& what) {
    ++failures;
    err << "penumbra-replay: " << what << "\n";
  };
  const MeshView& m = run->mesh();
  pnb_mesh_desc mesh PNB_MESH_DESC_INIT;
  mesh.points = m.points.data;
  mesh.point_count = static_cast<std::int64_t>(m.point_count());
  mesh.point_stride_bytes = m.points.stride_bytes;
  mesh.point_type = PNB_FLOAT64;
  mesh.connectivity = m.connectivity.data;
  mesh.connectivity_count = static_cast<std::int64_t>(m.connectivity.count);
  mesh.offsets = m.offsets.data;
  mesh.index_type = PNB_INT64;
  mesh.cell_types = m.cell_types;
  mesh.cell_types_count = static_cast<std::int64_t>(m.cell_type_count);
  mesh.topology_version = 1;
  if (pnb_publish_mesh(ctx, &mesh, PNB_BORROW) != PNB_OK) {
    fail(std::string("publish mesh: ") + pnb_last_error(ctx));
    pnb_destroy(ctx);
    return 1;
  }
  std::vector<std::vector<double>> values(run->fields().size());
  for (std::size_t s = first; s < last; ++s) {
    for (std::size_t f = 0; f < run->fields().size(); ++f) {
      const std::string& name = run->fields()[f];
      try {
        run->read(name, s, values[f]);
      } catch (const Error& e) {
        fail("step " + std::to_string(s) + ": " + e.what());
        continue;
      }
      pnb_field_desc field PNB_FIELD_DESC_INIT;
      field.name = name.c_str();
      field.association = PNB_POINT_FIELD;
      field.values = values[f].data();
      field.count = static_cast<std::int64_t>(values[f].size());
      field.components = 1;
      field.type = PNB_FLOAT64;
      if (pnb_publish_field(ctx, &field, PNB_BORROW) != PNB_OK)
        fail("step " + std::to_string(s) + ": publish field '" + name + "': " + pnb_last_error(ctx));
    }
    if (pnb_execute(ctx, run->time(s), run->cycle(s)) != PNB_OK)
      fail("step " + std::to_string(s) + ": execute: " + pnb_last_error(ctx));
    else if (!quiet)
      out << "  step " << s << " time " << run->time(s) << " cycle " << run->cycle(s) << "\n";
  }
  if (pnb_finalize(ctx) != PNB_OK) fail(std::string("finalize: ") + pnb_last_error(ctx));
  pnb_destroy(ctx);
  if (!quiet) out << "penumbra-replay: " << (last - first) << " step(s), " << failures << " failure(s)\n";
  return failures == 0 ? 0 : 1;
}

}  // namespace penumbra::replay

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

// The segments of a store directory in order, or `path` itself when it is a segment.
std::vector<std::string> segments_of(const std::string& path) {
  if (std::filesystem::exists(path + "/mesh.pnbm")) return {path};
  std::vector<std::string> segments;
  for (const auto& e : std::filesystem::directory_iterator(path))
    if (e.path().filename().string().rfind("segment-", 0) == 0) segments.push_back(e.path().string());
  std::sort(segments.begin(), segments.end());
  if (segments.empty()) throw Error(ErrorCode::io_error, "'" + path + "' holds no stored segment");
  return segments;
}

// The stored mesh as the C API takes it; `xyz` (xyz per point) replaces its points when given.
pnb_mesh_desc mesh_desc(const MeshView& m, const std::vector<double>* xyz, std::uint64_t version) {
  pnb_mesh_desc mesh PNB_MESH_DESC_INIT;
  mesh.points = xyz ? static_cast<const void*>(xyz->data()) : m.points.data;
  mesh.point_count = static_cast<std::int64_t>(m.point_count());
  mesh.point_stride_bytes = xyz ? 3 * static_cast<std::int64_t>(sizeof(double)) : m.points.stride_bytes;
  mesh.point_type = PNB_FLOAT64;
  mesh.connectivity = m.connectivity.data;
  mesh.connectivity_count = static_cast<std::int64_t>(m.connectivity.count);
  mesh.offsets = m.offsets.data;
  mesh.index_type = PNB_INT64;
  mesh.cell_types = m.cell_types;
  mesh.cell_types_count = static_cast<std::int64_t>(m.cell_type_count);
  mesh.topology_version = version;
  return mesh;
}

// Replays one segment's steps [first, last) into `ctx` as topology `version`: each step publishes
// the mesh (with the step's coordinates where the points move), the stored fields and executes.
class SegmentReplay {
public:
  SegmentReplay(pnb_context ctx, insitu::StoredRun& run, std::uint64_t version, bool quiet, std::ostream& out,
                std::ostream& err)
      : m_ctx(ctx), m_run(run), m_version(version), m_quiet(quiet), m_out(out), m_err(err), m_values(run.fields().size()) {}
  std::size_t failures() const { return m_failures; }

  void step(std::size_t s) {
    if (!publish_mesh(s)) return;
    for (std::size_t f = 0; f < m_run.fields().size(); ++f) publish_field(s, f);
    if (pnb_execute(m_ctx, m_run.time(s), m_run.cycle(s)) != PNB_OK)
      fail("step " + std::to_string(s) + ": execute: " + pnb_last_error(m_ctx));
    else if (!m_quiet)
      m_out << "  step " << s << " time " << m_run.time(s) << " cycle " << m_run.cycle(s) << "\n";
  }

private:
  void fail(const std::string& what) {
    ++m_failures;
    m_err << "penumbra-replay: " << what << "\n";
  }
  bool publish_mesh(std::size_t s) {
    const bool moving = m_run.points_move();
    try {
      if (moving) m_run.read_points(s, m_points);
    } catch (const Error& e) {
      fail("step " + std::to_string(s) + ": " + e.what());
      return false;
    }
    const pnb_mesh_desc mesh = mesh_desc(m_run.mesh(), moving ? &m_points : nullptr, m_version);
    if (pnb_publish_mesh(m_ctx, &mesh, PNB_BORROW) == PNB_OK) return true;
    fail("step " + std::to_string(s) + ": publish mesh: " + pnb_last_error(m_ctx));
    return false;
  }
  void publish_field(std::size_t s, std::size_t f) {
    const std::string& name = m_run.fields()[f];
    try {
      m_run.read(name, s, m_values[f]);
    } catch (const Error& e) {
      fail("step " + std::to_string(s) + ": " + e.what());
      return;
    }
    pnb_field_desc field PNB_FIELD_DESC_INIT;
    field.name = name.c_str();
    field.association = PNB_POINT_FIELD;
    field.values = m_values[f].data();
    field.count = static_cast<std::int64_t>(m_values[f].size());
    field.components = 1;
    field.type = PNB_FLOAT64;
    if (pnb_publish_field(m_ctx, &field, PNB_BORROW) != PNB_OK)
      fail("step " + std::to_string(s) + ": publish field '" + name + "': " + pnb_last_error(m_ctx));
  }

  pnb_context m_ctx;
  insitu::StoredRun& m_run;
  std::uint64_t m_version;
  bool m_quiet;
  std::ostream& m_out;
  std::ostream& m_err;
  std::vector<std::vector<double>> m_values;
  std::vector<double> m_points;
  std::size_t m_failures = 0;
};

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
  std::vector<std::unique_ptr<insitu::StoredRun>> runs;
  std::size_t total = 0;
  try {
    for (const std::string& segment : segments_of(path)) {
      runs.push_back(insitu::StoredRun::open(segment));
      total += runs.back()->step_count();
    }
  } catch (const Error& e) {
    err << "penumbra-replay: INPUT '" << path << "': " << e.what() << "\n";
    return 1;
  }
  const auto [first, last] = step_range(steps, total);
  if (!quiet)
    out << "penumbra-replay: stored run '" << path << "' (" << runs.size() << " segment(s), " << total
        << " step(s)), replaying steps " << first << ".." << last - 1 << "\n";
  pnb_context ctx = nullptr;
  if (pnb_create(config.c_str(), &ctx) != PNB_OK) {
    err << "penumbra-replay: " << pnb_last_error(nullptr) << "\n";
    return 1;
  }
  // Steps are numbered through the segments in order; each segment is a topology of its own.
  std::size_t failures = 0, begin = 0;
  for (std::size_t r = 0; r < runs.size(); ++r) {
    insitu::StoredRun& run = *runs[r];
    const std::size_t end = begin + run.step_count();
    const std::size_t from = std::max(first, begin), to = std::min(last, end);
    if (from < to) {
      if (!quiet && runs.size() > 1)
        out << " segment " << r << " (" << run.mesh().point_count() << " points" << (run.points_move() ? ", moving" : "")
            << ")\n";
      run.start_at(from - begin);  // the first pages load while the mesh is set up
      SegmentReplay replay(ctx, run, r + 1, quiet, out, err);
      for (std::size_t s = from; s < to; ++s) replay.step(s - begin);
      failures += replay.failures();
    }
    begin = end;
  }
  if (pnb_finalize(ctx) != PNB_OK) {
    ++failures;
    err << "penumbra-replay: finalize: " << pnb_last_error(ctx) << "\n";
  }
  pnb_destroy(ctx);
  if (!quiet) out << "penumbra-replay: " << (last - first) << " step(s), " << failures << " failure(s)\n";
  return failures == 0 ? 0 : 1;
}

}  // namespace penumbra::replay

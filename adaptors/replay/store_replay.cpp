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
#include "stored_segment.h"

namespace penumbra::replay {
namespace {

// A piece's mesh as the C API takes it.
pnb_mesh_desc mesh_desc(const StorePiece& piece, std::uint64_t version) {
  pnb_mesh_desc mesh PNB_MESH_DESC_INIT;
  mesh.points = piece.xyz().data();
  mesh.point_count = static_cast<std::int64_t>(piece.point_count());
  mesh.point_type = PNB_FLOAT64;
  mesh.connectivity = piece.connectivity().data();
  mesh.connectivity_count = static_cast<std::int64_t>(piece.connectivity().size());
  mesh.offsets = piece.offsets().data();
  mesh.index_type = PNB_INT64;
  mesh.cell_types = piece.cell_types().data();
  mesh.cell_types_count = static_cast<std::int64_t>(piece.cell_types().size());
  mesh.topology_version = version;
  return mesh;
}

// Replays one segment's steps [first, last) into `ctx` as topology `version`: each step publishes
// this rank's piece of the mesh (moved to the step's coordinates where the points move), the
// stored fields and executes.
class SegmentReplay {
public:
  SegmentReplay(pnb_context ctx, const StoredSegment& segment, StorePiece& piece, std::uint64_t version, bool quiet,
                std::ostream& out, std::ostream& err)
      : m_ctx(ctx), m_segment(segment), m_piece(piece), m_version(version), m_quiet(quiet), m_out(out), m_err(err),
        m_values(segment.fields().size()) {}
  std::size_t failures() const { return m_failures; }

  void step(std::size_t s) {
    publish_mesh(s);
    for (std::size_t f = 0; f < m_segment.fields().size(); ++f) publish_field(s, f);
    // Every rank executes, whatever failed here, so that no rank waits for another.
    if (pnb_execute(m_ctx, m_segment.time(s), m_segment.cycle(s)) != PNB_OK)
      fail("step " + std::to_string(s) + ": execute: " + pnb_last_error(m_ctx));
    else if (!m_quiet)
      m_out << "  step " << s << " time " << m_segment.time(s) << " cycle " << m_segment.cycle(s) << "\n";
  }

private:
  void fail(const std::string& what) {
    ++m_failures;
    m_err << "penumbra-replay: " << what << "\n";
  }
  void publish_mesh(std::size_t s) {
    try {
      if (m_segment.points_move()) m_piece.move_to(s);
    } catch (const Error& e) {
      fail("step " + std::to_string(s) + ": " + e.what());
    }
    const pnb_mesh_desc mesh = mesh_desc(m_piece, m_version);
    if (pnb_publish_mesh(m_ctx, &mesh, PNB_BORROW) != PNB_OK)
      fail("step " + std::to_string(s) + ": publish mesh: " + pnb_last_error(m_ctx));
  }
  void publish_field(std::size_t s, std::size_t f) {
    const std::string& name = m_segment.fields()[f];
    try {
      m_piece.read(name, s, m_values[f]);
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
  const StoredSegment& m_segment;
  StorePiece& m_piece;
  std::uint64_t m_version;
  bool m_quiet;
  std::ostream& m_out;
  std::ostream& m_err;
  std::vector<std::vector<double>> m_values;
  std::size_t m_failures = 0;
};

// A run restarted from a checkpoint begins a segment at a cycle an earlier segment holds: the
// earlier one's steps from there on were superseded.
void leave_out_superseded(std::vector<std::unique_ptr<StoredSegment>>& segments) {
  for (std::size_t i = 0; i + 1 < segments.size(); ++i) {
    StoredSegment& next = *segments[i + 1];
    if (next.step_count() == 0) continue;
    StoredSegment& s = *segments[i];
    std::size_t keep = 0;
    while (keep < s.step_count() && s.cycle(keep) < next.cycle(0)) ++keep;
    s.truncate(keep);
  }
}

}  // namespace

bool is_store(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_directory(path, ec)) return false;
  if (std::filesystem::exists(path + "/mesh.pnbm", ec) || std::filesystem::exists(path + "/parts.txt", ec)) return true;
  for (const auto& e : std::filesystem::directory_iterator(path, ec))
    if (e.path().filename().string().rfind("segment-", 0) == 0) return true;
  return false;
}

int replay_store(const std::string& config, const std::string& path, const std::string& steps, bool quiet,
                 std::ostream& out, std::ostream& err) {
  return replay_store(config, path, steps, quiet, out, err, ReplayRanks{0, 1, pnb_create});
}

int replay_store(const std::string& config, const std::string& path, const std::string& steps, bool quiet,
                 std::ostream& out, std::ostream& err, const ReplayRanks& ranks) {
  quiet = quiet || ranks.rank != 0;
  std::vector<std::unique_ptr<StoredSegment>> segments;
  std::size_t total = 0;
  try {
    for (const std::string& segment : store_segments(path)) segments.push_back(std::make_unique<StoredSegment>(segment));
    leave_out_superseded(segments);
    for (const auto& s : segments) total += s->step_count();
  } catch (const Error& e) {
    err << "penumbra-replay: INPUT '" << path << "': " << e.what() << "\n";
    return 1;
  }
  if (total == 0) {  // a run that died before its first window closed
    err << "penumbra-replay: INPUT '" << path << "' holds no finished step\n";
    return 1;
  }
  const auto [first, last] = step_range(steps, total);
  if (!quiet)
    out << "penumbra-replay: stored run '" << path << "' (" << segments.size() << " segment(s), " << total
        << " step(s)), replaying steps " << first << ".." << last - 1 << (ranks.ranks > 1 ? " over " + std::to_string(ranks.ranks) + " ranks" : "") << "\n";
  pnb_context ctx = nullptr;
  if (ranks.create(config.c_str(), &ctx) != PNB_OK) {
    err << "penumbra-replay: " << pnb_last_error(nullptr) << "\n";
    return 1;
  }
  // Steps are numbered through the segments in order; each segment is a topology of its own.
  std::size_t failures = 0, begin = 0;
  for (std::size_t r = 0; r < segments.size(); ++r) {
    const StoredSegment& segment = *segments[r];
    const std::size_t end = begin + segment.step_count();
    const std::size_t from = std::max(first, begin), to = std::min(last, end);
    if (from < to) {
      const std::size_t cells = segment.cell_count();
      StorePiece piece(segment, cells * static_cast<std::size_t>(ranks.rank) / static_cast<std::size_t>(ranks.ranks),
                       cells * static_cast<std::size_t>(ranks.rank + 1) / static_cast<std::size_t>(ranks.ranks));
      if (!quiet && segments.size() > 1)
        out << " segment " << r << " (" << segment.part_count() << " part(s), " << cells << " cells"
            << (segment.points_move() ? ", moving" : "") << ")\n";
      for (std::size_t p = 0; p < segment.part_count(); ++p) segment.part(p).start_at(from - begin);
      SegmentReplay replay(ctx, segment, piece, r + 1, quiet, out, err);
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

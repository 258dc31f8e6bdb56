// SPDX-License-Identifier: BSD-3-Clause
// adaptors/replay/stored_segment.cpp -- a segment's parts opened together, and a rank's piece of them
#include "stored_segment.h"

#include <algorithm>
#include <filesystem>
#include <fstream>

#include "penumbra/core/error.h"

namespace penumbra::replay {

std::vector<std::string> store_segments(const std::string& path) {
  if (std::filesystem::exists(path + "/mesh.pnbm") || std::filesystem::exists(path + "/parts.txt")) return {path};
  std::vector<std::string> segments;
  for (const auto& e : std::filesystem::directory_iterator(path))
    if (e.path().filename().string().rfind("segment-", 0) == 0) segments.push_back(e.path().string());
  std::sort(segments.begin(), segments.end());
  if (segments.empty()) throw Error(ErrorCode::io_error, "'" + path + "' holds no stored segment");
  return segments;
}

namespace {

// The part folders of a segment written over ranks, in order; empty for a serial segment.
std::vector<std::string> part_dirs(const std::string& dir) {
  if (std::filesystem::exists(dir + "/mesh.pnbm")) return {};
  std::ifstream count_file(dir + "/parts.txt");
  long long parts = 0;
  if (!(count_file >> parts) || parts < 1 || parts > (1 << 24))
    throw Error(ErrorCode::io_error, "stored segment '" + dir + "': no mesh.pnbm and no readable parts.txt");
  std::vector<std::string> dirs;
  for (long long p = 0; p < parts; ++p) {
    char name[32];
    std::snprintf(name, sizeof name, "/part-%05lld", p);
    dirs.push_back(dir + name);
    if (!std::filesystem::exists(dirs.back() + "/mesh.pnbm"))
      throw Error(ErrorCode::io_error, "stored segment '" + dir + "': part " + std::to_string(p) + " of " +
                                           std::to_string(parts) + " has no mesh.pnbm");
  }
  return dirs;
}

}  // namespace

StoredSegment::StoredSegment(const std::string& dir) : m_dir(dir) {
  std::vector<std::string> dirs = part_dirs(dir);
  if (dirs.empty()) dirs.push_back(dir);
  for (const std::string& d : dirs) m_parts.push_back(insitu::StoredRun::open(d));
  m_steps = m_parts.front()->step_count();
  // A part with no point (a rank that held no cell) keeps steps and no field.
  const insitu::StoredRun* with_points = nullptr;
  for (const auto& p : m_parts) {
    m_steps = std::min(m_steps, p->step_count());
    if (p->mesh().point_count() == 0) continue;
    if (!with_points) with_points = p.get();
    if (p->fields() != with_points->fields())
      throw Error(ErrorCode::io_error, "stored segment '" + dir + "': its parts store different fields");
  }
  if (!with_points) throw Error(ErrorCode::io_error, "stored segment '" + dir + "': no part has a cell");
  m_fields = with_points->fields();
  for (std::size_t s = 0; s < m_steps; ++s)
    for (const auto& p : m_parts)
      if (p->cycle(s) != m_parts.front()->cycle(s))
        throw Error(ErrorCode::io_error, "stored segment '" + dir + "': its parts differ at step " + std::to_string(s) +
                                             " (cycles " + std::to_string(m_parts.front()->cycle(s)) + " and " +
                                             std::to_string(p->cycle(s)) + ")");
}

bool StoredSegment::points_move() const {
  return std::any_of(m_parts.begin(), m_parts.end(), [](const auto& p) { return p->points_move(); });
}

std::size_t StoredSegment::cell_count() const {
  std::size_t n = 0;
  for (const auto& p : m_parts) n += p->mesh().cell_count();
  return n;
}

void StoredSegment::truncate(std::size_t steps) { m_steps = std::min(m_steps, steps); }

StorePiece::StorePiece(const StoredSegment& segment, std::size_t first_cell, std::size_t last_cell) : m_segment(segment) {
  m_offsets.push_back(0);
  std::size_t part_first = 0;
  for (std::size_t p = 0; p < segment.part_count(); ++p) {
    const MeshView& m = segment.part(p).mesh();
    const std::size_t cells = m.cell_count(), part_last = part_first + cells;
    const std::size_t from = std::max(first_cell, part_first), to = std::min(last_cell, part_last);
    if (from < to) {
      m_parts.push_back(p);
      const auto base = static_cast<std::int64_t>(point_count());
      for (std::size_t i = 0; i < m.point_count(); ++i) {
        const Vec3d x = m.point(i);
        m_xyz.insert(m_xyz.end(), {x.x, x.y, x.z});
      }
      for (std::size_t c = from - part_first; c < to - part_first; ++c) {
        const auto end = c + 1 < cells ? m.cell_begin(c + 1) : static_cast<std::int64_t>(m.connectivity.count);
        for (auto k = m.cell_begin(c); k < end; ++k) m_connectivity.push_back(base + m.connectivity[static_cast<std::size_t>(k)]);
        m_offsets.push_back(static_cast<std::int64_t>(m_connectivity.size()));
        m_types.push_back(m.cell_type(c));
      }
    }
    part_first = part_last;
  }
}

void StorePiece::move_to(std::size_t step) {
  std::size_t at = 0;
  for (std::size_t p : m_parts) {
    insitu::StoredRun& run = m_segment.part(p);
    run.read_points(step, m_part_values);
    std::copy(m_part_values.begin(), m_part_values.end(), m_xyz.begin() + static_cast<std::ptrdiff_t>(at));
    at += m_part_values.size();
  }
}

void StorePiece::read(const std::string& field, std::size_t step, std::vector<double>& out) {
  out.clear();
  for (std::size_t p : m_parts) {
    m_segment.part(p).read(field, step, m_part_values);
    out.insert(out.end(), m_part_values.begin(), m_part_values.end());
  }
}

}  // namespace penumbra::replay

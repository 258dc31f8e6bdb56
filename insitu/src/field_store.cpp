// SPDX-License-Identifier: BSD-3-Clause
// insitu/src/field_store.cpp -- segments, per-field streaming encoders and the step list
#include "field_store.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "penumbra/core/error.h"
#include "coordinate_store.h"
#include "steps_csv.h"
#include "stored_mesh.h"

namespace penumbra::insitu {
namespace {

// A field name as a file name: anything but letters, digits, '-', '_' and '.' becomes '_'
// (the field's real name is kept in its file's header).
std::string file_stem(const std::string& name) {
  std::string s = name;
  for (char& c : s)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' || c == '.')) c = '_';
  return s.empty() || s[0] == '.' ? "_" + s : s;
}

// The part count of a segment over several ranks, through a temporary file renamed into place.
void write_part_count(const std::string& path, int parts) {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp, std::ios::trunc);
    out << parts << "\n";
    out.flush();
    if (!out) throw Error(ErrorCode::io_error, "store: cannot write '" + tmp + "'");
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) throw Error(ErrorCode::io_error, "store: cannot rename '" + tmp + "' to '" + path + "': " + ec.message());
}

}  // namespace

FieldStore::FieldStore(StoreConfig config, int part, int parts) : m_config(std::move(config)), m_part(part), m_parts(parts) {
  std::error_code ec;
  std::filesystem::create_directories(m_config.directory, ec);
  if (ec || !std::filesystem::is_directory(m_config.directory))
    throw Error(ErrorCode::io_error, "store: cannot create directory '" + m_config.directory + "'" +
                                         (ec ? ": " + ec.message() : std::string()));
  // A new run never mixes its segments with an earlier run's: continue numbering after them.
  for (const auto& e : std::filesystem::directory_iterator(m_config.directory, ec)) {
    const std::string n = e.path().filename().string();
    if (n.rfind("segment-", 0) == 0) m_segment = std::max(m_segment, std::atoi(n.c_str() + 8));
  }
}

FieldStore::~FieldStore() {
  try {
    finish();
  } catch (...) {
    // Destruction must not throw; the .partial files keep every finished window.
  }
}

bool FieldStore::records(std::int64_t cycle) const { return cycle % m_config.every_cycles == 0; }

void FieldStore::begin_segment(const MeshView& mesh) {
  finish();
  m_encoders.clear();
  m_steps.clear();
  m_moving = false;
  m_coordinates.reset();
  ++m_segment;
  char name[32];
  std::snprintf(name, sizeof name, "segment-%03d", m_segment);
  m_segment_dir = m_config.directory + "/" + name;
  const std::string segment_dir = m_segment_dir;
  if (m_parts > 1) {
    char part[32];
    std::snprintf(part, sizeof part, "/part-%05d", m_part);
    m_segment_dir += part;
  }
  std::error_code ec;
  std::filesystem::create_directories(m_segment_dir, ec);
  if (ec) throw Error(ErrorCode::io_error, "store: cannot create '" + m_segment_dir + "': " + ec.message());
  if (m_parts > 1 && m_part == 0) write_part_count(segment_dir + "/parts.txt", m_parts);
  m_point_count = mesh.point_count();
  write_stored_mesh(m_segment_dir + "/mesh.pnbm", copy_mesh(mesh));
  write_steps();
}

void FieldStore::record_points(double time, std::int64_t cycle, const std::vector<Vec3d>& points, double thinnest_altitude) {
  if (m_segment_dir.empty()) throw Error(ErrorCode::invalid_operation, "store: no mesh published yet");
  if (m_point_count == 0) return;  // an empty part (a rank with no cell) has no coordinates to keep
  if (!m_coordinates) m_coordinates = std::make_unique<CoordinateWriter>(m_segment_dir + "/coordinates", m_point_count, m_config);
  try {
    m_coordinates->record(time, cycle, points, thinnest_altitude);
  } catch (const Error& e) {
    throw Error(e.code(), "store: the coordinates at cycle " + std::to_string(cycle) + ": " + e.what());
  }
}

void FieldStore::record(const std::string& field, double time, std::int64_t cycle, const std::vector<double>& values) {
  if (m_segment_dir.empty()) throw Error(ErrorCode::invalid_operation, "store: no mesh published yet");
  require(values.size() == m_point_count, "store: field '" + field + "' has " + std::to_string(values.size()) +
                                              " values for " + std::to_string(m_point_count) + " points");
  // An empty part (a rank with no cell) keeps its steps only, so that its segment's parts agree.
  if (m_point_count == 0) return record_step(time, cycle);
  auto& enc = m_encoders[field];
  if (!enc) {
    compression::StreamingOptions o;
    o.path = m_segment_dir + "/" + file_stem(field) + ".pnbf";
    o.field_name = field;
    o.vertex_count = m_point_count;
    o.codec = m_config.codec;
    o.memory_budget_bytes = m_config.memory_budget_bytes;
    try {
      enc = std::make_unique<compression::StreamingEncoder>(o);
    } catch (...) {
      m_encoders.erase(field);
      throw;
    }
  }
  try {
    enc->push(time, values.data());
  } catch (const Error& e) {
    throw Error(e.code(), "store: field '" + field + "' at cycle " + std::to_string(cycle) + ": " + e.what());
  }
  record_step(time, cycle);
}

void FieldStore::record_step(double time, std::int64_t cycle) {
  if (m_steps.empty() || m_steps.back().first != cycle) {
    m_steps.emplace_back(cycle, time);
    write_steps();
  }
}

void FieldStore::write_steps() { write_steps_csv(m_segment_dir + "/steps.csv", m_steps); }

void FieldStore::finish() {
  std::string failures;
  if (m_coordinates) {
    try {
      m_coordinates->finish();
    } catch (const Error& e) {
      failures = e.what();
    }
  }
  for (auto& [name, enc] : m_encoders) {
    try {
      enc->finish();
    } catch (const Error& e) {
      failures += (failures.empty() ? "" : "; ") + std::string(e.what());
    }
  }
  if (!failures.empty()) throw Error(ErrorCode::io_error, "store: " + failures);
}

}  // namespace penumbra::insitu

// SPDX-License-Identifier: BSD-3-Clause
// insitu/src/field_store.cpp -- segments, per-field streaming encoders and the step list
#include "field_store.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>

#include "penumbra/core/error.h"
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

// The values as float32, in which the store keeps them (NaN stays NaN: the encoder reports it).
// Refused instead, in one pass over the values:
// - a finite value beyond float32's range, which would become infinite (named with its point);
// - a field whose values are far larger than their variation (an absolute temperature, a pressure
//   with a large ambient part) and so lose that variation in the narrowing: when the narrowing
//   alone moves a value by more than the configured error bound, or, without a bound, by more than
//   1e-4 of the step's range (a tenth of what the VQ codec itself costs on smooth fields), instead
//   of storing a history that replays wrong.
std::vector<float> narrow_for_store(const std::vector<double>& values, const compression::ErrorBound& bound,
                                    const std::string& who) {
  std::vector<float> out(values.size());
  double lo = std::numeric_limits<double>::infinity(), hi = -lo, worst = 0, at = 0;
  for (std::size_t i = 0; i < values.size(); ++i) {
    const double v = values[i];
    if (std::isfinite(v) && std::fabs(v) > std::numeric_limits<float>::max()) {
      char text[160];
      std::snprintf(text, sizeof text, ": point %zu has the value %.17g, beyond float32's range (|v| <= %.9g) in which the store keeps values",
                    i, v, static_cast<double>(std::numeric_limits<float>::max()));
      throw Error(ErrorCode::invalid_argument, who + text);
    }
    out[i] = static_cast<float>(v);
    if (!std::isfinite(v)) continue;
    lo = std::min(lo, v);
    hi = std::max(hi, v);
    const double e = std::fabs(v - static_cast<double>(out[i]));
    if (e > worst) {
      worst = e;
      at = v;
    }
  }
  const double range = hi - lo;
  if (!(range > 0)) return out;  // constant: float32 holds its one value as well as it can
  const double allowed = bound.kind == compression::BoundKind::absolute         ? bound.value
                         : bound.kind == compression::BoundKind::range_relative ? bound.value * range
                                                                                : 1e-4 * range;
  if (worst <= allowed) return out;
  char text[400];
  std::snprintf(text, sizeof text,
                ": float32, in which the store keeps values, moves them by up to %.3g (at %.9g) while they vary by %.3g, "
                "beyond the %.3g the store may lose (%s); store the field minus a reference value, or render it in situ only",
                worst, at, range, allowed, bound.kind == compression::BoundKind::none ? "1e-4 of the range without an error bound" : "its error bound");
  throw Error(ErrorCode::invalid_argument, who + text);
}

}  // namespace

FieldStore::FieldStore(StoreConfig config) : m_config(std::move(config)) {
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
  ++m_segment;
  char name[32];
  std::snprintf(name, sizeof name, "segment-%03d", m_segment);
  m_segment_dir = m_config.directory + "/" + name;
  std::error_code ec;
  std::filesystem::create_directories(m_segment_dir, ec);
  if (ec) throw Error(ErrorCode::io_error, "store: cannot create '" + m_segment_dir + "': " + ec.message());
  m_point_count = mesh.point_count();
  write_stored_mesh(m_segment_dir + "/mesh.pnbm", copy_mesh(mesh));
  write_steps();
}

void FieldStore::record(const std::string& field, double time, std::int64_t cycle, const std::vector<double>& values) {
  if (m_segment_dir.empty()) throw Error(ErrorCode::invalid_operation, "store: no mesh published yet");
  require(values.size() == m_point_count, "store: field '" + field + "' has " + std::to_string(values.size()) +
                                              " values for " + std::to_string(m_point_count) + " points");
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
  const std::string who = "store: field '" + field + "' at cycle " + std::to_string(cycle);
  const std::vector<float> narrowed = narrow_for_store(values, m_config.codec.bound, who);
  try {
    enc->push(time, narrowed.data());
  } catch (const Error& e) {
    throw Error(e.code(), "store: field '" + field + "' at cycle " + std::to_string(cycle) + ": " + e.what());
  }
  if (m_steps.empty() || m_steps.back().first != cycle) {
    m_steps.emplace_back(cycle, time);
    write_steps();
  }
}

void FieldStore::write_steps() {
  // Rewritten whole and renamed into place: a reader never sees a half-written list.
  const std::string path = m_segment_dir + "/steps.csv", tmp = path + ".tmp";
  {
    std::ofstream out(tmp, std::ios::trunc);
    out << "cycle,time\n";
    char line[64];
    for (const auto& [cycle, time] : m_steps) {
      std::snprintf(line, sizeof line, "%lld,%.17g\n", static_cast<long long>(cycle), time);
      out << line;
    }
    out.flush();
    if (!out) throw Error(ErrorCode::io_error, "store: cannot write '" + tmp + "' (disk full?)");
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) throw Error(ErrorCode::io_error, "store: cannot rename '" + tmp + "': " + ec.message());
}

void FieldStore::finish() {
  std::string failures;
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

// SPDX-License-Identifier: BSD-3-Clause
// insitu/src/cinema_database.cpp -- data.csv reading, atomic rewriting, image naming
#include "cinema_database.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "atomic_file.h"
#include "penumbra/core/error.h"

namespace penumbra::insitu {
namespace fs = std::filesystem;
namespace {

constexpr const char* kCsvName = "data.csv";

[[noreturn]] void io_fail(const std::string& what, const std::string& path, int err) {
  throw Error(ErrorCode::io_error, "Cinema database: " + what + " '" + path + "': " + std::strerror(err));
}

std::string csv_quote(const std::string& s) {
  if (s.find_first_of(",\"\r\n") == std::string::npos) return s;
  std::string q = "\"";
  for (char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

std::string row_key(const std::vector<std::string>& values) {
  std::string k;
  for (const auto& v : values) k += csv_quote(v) + ",";
  return k;
}

/// True for "name.tmp.<pid>": a temporary file of an atomic write (ours or write_png's).
bool is_leftover_temp(const std::string& name) {
  const auto at = name.rfind(".tmp.");
  if (at == std::string::npos || at + 5 == name.size()) return false;
  for (std::size_t i = at + 5; i < name.size(); ++i)
    if (name[i] < '0' || name[i] > '9') return false;
  return true;
}

/// Removes temporary files that a killed writer left in `dir` and its image folders; they were
/// never listed in data.csv.
void remove_leftover_temps(const fs::path& dir) {
  std::error_code ec;
  for (fs::recursive_directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    if (it.depth() >= 1) it.disable_recursion_pending();  // the directory and its image folders only
    if (it->is_regular_file(ec) && is_leftover_temp(it->path().filename().string())) fs::remove(it->path(), ec);
  }
}

}  // namespace

std::string safe_path_component(const std::string& s) {
  std::string out;
  for (char c : s) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '-' ||
                    c == '_' || c == '.';
    out += ok ? c : '_';
  }
  if (out.empty() || out == "." || out == "..") out = "_" + out;
  return out;
}

std::vector<std::vector<std::string>> CinemaDatabase::parse_csv(const std::string& text, const std::string& source) {
  std::vector<std::vector<std::string>> rows;
  std::vector<std::string> row;
  std::string cell;
  bool quoted = false, row_started = false;
  std::size_t line = 1;
  auto fail = [&](const std::string& what) {
    throw Error(ErrorCode::invalid_argument, "Cinema database: " + source + " line " + std::to_string(line) + ": " + what);
  };
  auto end_row = [&] {
    row.push_back(cell);
    cell.clear();
    if (!rows.empty() && row.size() != rows.front().size())
      fail("has " + std::to_string(row.size()) + " columns, the header has " + std::to_string(rows.front().size()));
    rows.push_back(std::move(row));
    row.clear();
    row_started = false;
  };
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (quoted) {
      if (c == '"' && i + 1 < text.size() && text[i + 1] == '"') {
        cell += '"';
        ++i;
      } else if (c == '"') {
        quoted = false;
      } else {
        if (c == '\n') ++line;
        cell += c;
      }
      continue;
    }
    if (c == '"') {
      if (!cell.empty()) fail("has a quote inside an unquoted value");
      quoted = row_started = true;
    } else if (c == ',') {
      row.push_back(cell);
      cell.clear();
      row_started = true;
    } else if (c == '\n') {
      end_row();
      ++line;
    } else if (c != '\r') {
      cell += c;
      row_started = true;
    }
  }
  if (quoted) fail("ends inside a quoted value");
  if (row_started) end_row();
  return rows;
}

CinemaDatabase::CinemaDatabase(std::string directory, std::vector<std::string> parameters, IfExists if_exists,
                               std::size_t annotations)
    : m_directory(std::move(directory)), m_parameters(std::move(parameters)), m_annotations(annotations) {
  std::error_code ec;
  const fs::path dir(m_directory);
  const bool exists = fs::exists(dir, ec);
  if (exists && !fs::is_directory(dir, ec))
    throw Error(ErrorCode::io_error, "Cinema database: output directory '" + m_directory + "' exists and is not a directory");
  const fs::path csv = dir / kCsvName;
  if (exists && if_exists == IfExists::error && !fs::is_empty(dir, ec))
    throw Error(ErrorCode::invalid_argument,
                "Cinema database: output directory '" + m_directory +
                    "' exists and is not empty; refusing to overwrite it (set output.if_exists to \"resume\" "
                    "to append to its database, or choose another directory)");
  if (!exists && !fs::create_directories(dir, ec))
    io_fail("cannot create output directory", m_directory, ec.value());
  if (exists && if_exists == IfExists::resume) {
    if (fs::exists(csv, ec)) load_existing(csv.string());
    remove_leftover_temps(dir);
  }
  write_csv();  // proves the directory writable now, not at the first rendered step
}

void CinemaDatabase::load_existing(const std::string& csv_path) {
  std::ifstream in(csv_path, std::ios::binary);
  if (!in) io_fail("cannot read", csv_path, errno);
  std::ostringstream ss;
  ss << in.rdbuf();
  const auto table = parse_csv(ss.str(), "'" + csv_path + "'");
  std::vector<std::string> expected = m_parameters;
  expected.push_back("FILE");
  auto joined = [](const std::vector<std::string>& v) {
    std::string s;
    for (const auto& x : v) s += (s.empty() ? "" : ",") + x;
    return s;
  };
  if (table.empty() || table.front() != expected)
    throw Error(ErrorCode::invalid_argument,
                "Cinema database: cannot resume '" + csv_path + "': its header is '" +
                    (table.empty() ? std::string() : joined(table.front())) + "' but this config writes '" +
                    joined(expected) + "' (use a new output directory for a different camera or parameter set)");
  for (std::size_t r = 1; r < table.size(); ++r) {
    Row row{std::vector<std::string>(table[r].begin(), table[r].end() - 1), table[r].back()};
    m_row_of_key[key_of(row.values)] = m_rows.size();
    m_rows.push_back(std::move(row));
  }
}

std::string CinemaDatabase::key_of(const std::vector<std::string>& values) const {
  const std::size_t n = values.size() > m_annotations ? values.size() - m_annotations : 0;
  return row_key(std::vector<std::string>(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(n)));
}

std::string CinemaDatabase::new_image_path(const std::string& subdir, const std::string& stem) {
  const std::string sub = safe_path_component(subdir);
  std::error_code ec;
  const fs::path dir = fs::path(m_directory) / sub;
  fs::create_directories(dir, ec);
  if (ec) io_fail("cannot create image directory", dir.string(), ec.value());
  const std::string base = safe_path_component(stem);
  for (int n = 1;; ++n) {
    std::string rel = sub + "/" + base;
    if (n > 1) rel.append(1, '_').append(std::to_string(n));
    rel += ".png";
    if (m_reserved.count(rel) || fs::exists(fs::path(m_directory) / rel, ec)) continue;
    m_reserved.insert(rel);
    return rel;
  }
}

void CinemaDatabase::commit(const std::vector<Row>& rows) {
  for (const auto& row : rows) {
    PNB_ASSERT(row.values.size() == m_parameters.size());
    const std::string key = key_of(row.values);
    auto it = m_row_of_key.find(key);
    if (it != m_row_of_key.end()) {
      m_rows[it->second] = row;
    } else {
      m_row_of_key[key] = m_rows.size();
      m_rows.push_back(row);
    }
  }
  write_csv();
  m_reserved.clear();
}

std::string CinemaDatabase::path_of(const std::string& relative) const {
  return (fs::path(m_directory) / relative).string();
}

void CinemaDatabase::write_csv() const {
  std::string text;
  for (const auto& p : m_parameters) text += csv_quote(p) + ",";
  text += "FILE\n";
  for (const auto& row : m_rows) {
    for (const auto& v : row.values) text += csv_quote(v) + ",";
    text += csv_quote(row.file) + "\n";
  }
  write_file_atomic(path_of(kCsvName), text);
}

}  // namespace penumbra::insitu

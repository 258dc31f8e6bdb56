// SPDX-License-Identifier: BSD-3-Clause
// insitu/src/cinema_database.h -- Cinema spec D image database, kill-safe
#pragma once
#include <string>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "config.h"

namespace penumbra::insitu {

/// A Cinema spec D database: a directory holding `data.csv` (one column per parameter, then a
/// final FILE column with image paths relative to the directory) and the images.
///
/// Kill safety: images are written (by the caller) with temp file + rename before commit()
/// lists them, and commit() rewrites data.csv to a temporary file, fsyncs it, renames it into
/// place and fsyncs the directory. Killing the process at any moment therefore leaves a valid
/// database listing every committed step; at worst an image of an uncommitted step lies
/// unlisted beside it. Not thread-safe. Throws penumbra::Error.
class CinemaDatabase {
public:
  /// One image: its parameter values (in column order) and its path relative to the directory.
  struct Row {
    std::vector<std::string> values;
    std::string file;
  };

  /// Opens `directory` with parameter columns `parameters` (FILE is appended).
  /// - IfExists::error: a missing or empty directory is used; a non-empty one is refused with
  ///   Error(invalid_argument) telling how to resume.
  /// - IfExists::resume: an existing data.csv is read and later steps are appended; a header
  ///   that does not match `parameters` is refused with Error(invalid_argument). Temporary
  ///   files (`*.tmp.<pid>`) left by a killed writer are removed.
  /// Writes data.csv immediately (header at least), so an unwritable directory fails here with
  /// Error(io_error) naming the path. The last `annotations` parameters describe an image without
  /// telling it apart from others (`degraded`): rows are the same image when the others match.
  CinemaDatabase(std::string directory, std::vector<std::string> parameters, IfExists if_exists,
                 std::size_t annotations = 0);

  /// A new image path relative to the directory, `subdir/stem.png`, or `subdir/stem_2.png`, ...
  /// when taken on disk or earlier in this step: an existing file is never overwritten. Creates
  /// `subdir`.
  std::string new_image_path(const std::string& subdir, const std::string& stem);

  /// Lists `rows` in data.csv and rewrites it atomically. A row whose parameter values equal an
  /// existing row's replaces it (a resumed run re-rendering a step); the old image stays on disk.
  void commit(const std::vector<Row>& rows);

  /// Absolute (directory-joined) path of a relative database path.
  std::string path_of(const std::string& relative) const;
  const std::string& directory() const { return m_directory; }
  const std::vector<Row>& rows() const { return m_rows; }

  /// Parses a data.csv text (RFC 4180 quoting); first row is the header. Throws
  /// Error(invalid_argument) naming `source` and the line on ragged rows or bad quoting.
  static std::vector<std::vector<std::string>> parse_csv(const std::string& text, const std::string& source);

private:
  void load_existing(const std::string& csv_path);
  void write_csv() const;

  std::string m_directory;
  std::vector<std::string> m_parameters;
  std::size_t m_annotations = 0;
  std::string key_of(const std::vector<std::string>& values) const;
  std::vector<Row> m_rows;
  std::unordered_map<std::string, std::size_t> m_row_of_key;
  std::unordered_set<std::string> m_reserved;
};

/// Makes `s` safe as one path component: letters, digits, '-', '_' and '.' are kept, anything
/// else becomes '_'; never empty, never "." or "..".
std::string safe_path_component(const std::string& s);

}  // namespace penumbra::insitu

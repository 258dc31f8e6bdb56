// SPDX-License-Identifier: BSD-3-Clause
// insitu/src/atomic_file.h -- small files replaced whole or not at all
#pragma once
#include <string>

namespace penumbra::insitu {

/// Writes `text` to `path` durably: a temporary file in the same directory, fsync, rename, fsync
/// of the directory, so that a crash leaves the old file or the new one. Throws
/// Error(io_error) naming the file, with `what` (e.g. "Cinema database") first.
void write_file_atomic(const std::string& path, const std::string& text, const std::string& what = "Cinema database");

}  // namespace penumbra::insitu

// SPDX-License-Identifier: BSD-3-Clause
// viewer/src/request_path.h -- which file inside the database a request names, if any
#pragma once
#include <filesystem>
#include <optional>
#include <string>

namespace penumbra::viewer {

/// The longest request path served (bytes, still percent-encoded).
inline constexpr std::size_t kMaxRequestPath = 1024;

/// The regular file inside `root` that `target` names (the URL path below the database's prefix,
/// still percent-encoded), or nothing when it is not one: an over-long path, a bad percent
/// escape, a NUL or a backslash, an absolute path, an empty, `.` or `..` segment (after decoding,
/// so `%2e%2e` too), or a path whose real location (symbolic links followed) is not inside the
/// real `root`. `root` must exist.
std::optional<std::filesystem::path> resolve_in(const std::filesystem::path& root, const std::string& target);

/// `text` with %XX escapes decoded, or nothing for a malformed escape or a decoded NUL.
std::optional<std::string> percent_decoded(const std::string& text);

}  // namespace penumbra::viewer

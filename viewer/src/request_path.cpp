// SPDX-License-Identifier: BSD-3-Clause
// viewer/src/request_path.cpp -- request paths checked segment by segment, then by their real location
#include "request_path.h"

#include <sstream>
#include <vector>

namespace penumbra::viewer {
namespace {

int hex_value(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

// Whether `inner` (a real path) lies inside `outer` (a real directory).
bool inside(const std::filesystem::path& outer, const std::filesystem::path& inner) {
  auto o = outer.begin(), i = inner.begin();
  for (; o != outer.end(); ++o, ++i)
    if (i == inner.end() || *o != *i) return false;
  return true;
}

}  // namespace

std::optional<std::string> percent_decoded(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  for (std::size_t i = 0; i < text.size(); ++i) {
    char c = text[i];
    if (c == '%') {
      if (i + 2 >= text.size()) return std::nullopt;
      const int hi = hex_value(text[i + 1]), lo = hex_value(text[i + 2]);
      if (hi < 0 || lo < 0) return std::nullopt;
      c = static_cast<char>(hi * 16 + lo);
      i += 2;
    }
    if (c == '\0') return std::nullopt;
    out.push_back(c);
  }
  return out;
}

std::optional<std::filesystem::path> resolve_in(const std::filesystem::path& root, const std::string& target) {
  if (target.empty() || target.size() > kMaxRequestPath) return std::nullopt;
  const std::optional<std::string> decoded = percent_decoded(target);
  if (!decoded || decoded->empty() || decoded->front() == '/' || decoded->find('\\') != std::string::npos) return std::nullopt;
  std::filesystem::path relative;
  std::stringstream segments(*decoded);
  for (std::string segment; std::getline(segments, segment, '/');) {
    if (segment.empty() || segment == "." || segment == "..") return std::nullopt;
    relative /= segment;
  }
  if (decoded->back() == '/') return std::nullopt;
  std::error_code ec;
  const std::filesystem::path real_root = std::filesystem::canonical(root, ec);
  if (ec) return std::nullopt;
  const std::filesystem::path real = std::filesystem::canonical(real_root / relative, ec);
  if (ec || !inside(real_root, real) || !std::filesystem::is_regular_file(real, ec)) return std::nullopt;
  return real;
}

}  // namespace penumbra::viewer

// SPDX-License-Identifier: BSD-3-Clause
// tests/unit/insitu/test_util.h -- temporary directories and config snippets for insitu tests
#pragma once
#include <stdlib.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace penumbra::insitu::testing {

/// A fresh directory under the system temp dir, removed with everything in it at scope exit.
class TempDir {
public:
  TempDir() {
    std::string pattern = (std::filesystem::temp_directory_path() / "pnb-insitu-XXXXXX").string();
    m_path = ::mkdtemp(pattern.data()) ? pattern : std::string();
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(m_path, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::string& path() const { return m_path; }
  std::string operator/(const std::string& name) const { return m_path + "/" + name; }

private:
  std::string m_path;
};

inline std::string read_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

/// A small valid config rendering `fields` (a JSON array text) into `dir`.
inline std::string small_config(const std::string& dir, const std::string& fields = R"([{"name": "T"}])",
                                const std::string& extra = "") {
  return R"({"output": {"directory": ")" + dir + R"("}, "image": {"width": 24, "height": 20},
             "cameras": {"phi": [0, 90], "theta": [30]}, "fields": )" + fields + extra + "}";
}

}  // namespace penumbra::insitu::testing

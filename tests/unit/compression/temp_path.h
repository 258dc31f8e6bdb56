// SPDX-License-Identifier: BSD-3-Clause
// tests/unit/compression/temp_path.h -- unique scratch file paths for the compression tests.
#pragma once
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

namespace penumbra::compression::testing {

/// Removes every scratch file a test asked for (and its `.partial` and `.tmp` siblings) when the
/// test ends, whatever its outcome.
class ScratchCleaner : public ::testing::EmptyTestEventListener {
public:
  static ScratchCleaner& instance() {
    // Owned by gtest's listener list once appended.
    static ScratchCleaner* cleaner = [] {
      auto* c = new ScratchCleaner;
      ::testing::UnitTest::GetInstance()->listeners().Append(c);
      return c;
    }();
    return *cleaner;
  }
  void add(const std::string& path) { m_paths.push_back(path); }
  void OnTestEnd(const ::testing::TestInfo&) override {
    for (const auto& p : m_paths)
      for (const char* suffix : {"", ".partial", ".tmp"}) std::remove((p + suffix).c_str());
    m_paths.clear();
  }

private:
  std::vector<std::string> m_paths;
};

inline std::string temp_path(const std::string& stem) {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  std::string path = ::testing::TempDir() + "pnb_" + std::to_string(::getpid()) + "_" + info->name() + "_" + stem;
  ScratchCleaner::instance().add(path);
  return path;
}

inline std::vector<char> read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

inline void write_file(const std::string& path, const char* data, std::size_t size) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(data, std::streamsize(size));
}

}  // namespace penumbra::compression::testing

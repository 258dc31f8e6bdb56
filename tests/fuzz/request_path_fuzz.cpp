// SPDX-License-Identifier: BSD-3-Clause
// tests/fuzz/request_path_fuzz.cpp -- penumbra-view's request paths (resolve_in): whatever the
// bytes, a path that resolves is a regular file inside the database, never the file beside it.
#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

#include "fuzz_util.h"
#include "request_path.h"

namespace {

namespace fs = std::filesystem;

// A database with a nested image, a secret beside it and links leading out, made once.
const fs::path& database() {
  static const fs::path db = [] {
    const fs::path dir = fs::temp_directory_path() / ("pnb_fuzz_request_path_" + std::to_string(::getpid()));
    fs::create_directories(dir / "db" / "T");
    std::ofstream(dir / "db" / "data.csv") << "time,FILE\n0,T/a.png\n";
    std::ofstream(dir / "db" / "T" / "a.png") << "png";
    std::ofstream(dir / "secret.txt") << "secret";
    std::error_code ec;
    fs::create_symlink(dir / "secret.txt", dir / "db" / "out.txt", ec);
    fs::create_directory_symlink(dir, dir / "db" / "up", ec);
    return fs::canonical(dir / "db");
  }();
  return db;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string target(reinterpret_cast<const char*>(data), size);
  const auto file = penumbra::viewer::resolve_in(database(), target);
  if (!file) return 0;
  const std::string root = database().string() + "/", found = file->string();
  if (found.compare(0, root.size(), root) != 0) penumbra::fuzz::fail("resolve_in left the database: " + found);
  if (!fs::is_regular_file(*file)) penumbra::fuzz::fail("resolve_in gave something that is not a regular file: " + found);
  if (target.size() > penumbra::viewer::kMaxRequestPath) penumbra::fuzz::fail("resolve_in took an over-long path");
  return 0;
}

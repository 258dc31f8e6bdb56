// SPDX-License-Identifier: BSD-3-Clause
// tests/fuzz/fuzz_util.h -- what several harnesses share: a temporary folder of the process's own
// for the readers that take a path, how a harness reports a bug, and little-endian field access
// for the binary formats
#pragma once
#include <stdlib.h>

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "penumbra/core/error.h"

namespace penumbra::fuzz {

/// A folder of this process's own under $TMPDIR (else /tmp), made at the first call and removed
/// with everything in it when the process exits normally. Harnesses write the bytes of readers
/// that take a path there, never into the repository.
inline const std::string& temp_dir() {
  struct Folder {
    std::string path;
    Folder() {
      const char* tmp = std::getenv("TMPDIR");
      std::string pattern = std::string(tmp && *tmp ? tmp : "/tmp") + "/pnb-fuzz-XXXXXX";
      if (!::mkdtemp(pattern.data())) {
        std::perror("pnb fuzz: mkdtemp");
        std::abort();
      }
      path = pattern;
    }
    ~Folder() {
      std::error_code ec;
      std::filesystem::remove_all(path, ec);
    }
  };
  static const Folder folder;
  return folder.path;
}

/// Writes `size` bytes to `path` (replacing it); aborts when it cannot, which is the harness's
/// fault, not the reader's.
inline void write_file(const std::string& path, const void* data, std::size_t size) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f || (size > 0 && std::fwrite(data, 1, size, f) != size) || std::fclose(f) != 0) {
    std::perror(("pnb fuzz: cannot write " + path).c_str());
    std::abort();
  }
}

/// Reports a bug of the code under test and stops: libFuzzer keeps the input that got here.
[[noreturn]] inline void fail(const std::string& what) {
  std::fprintf(stderr, "%s\n", what.c_str());
  std::abort();
}

/// An Error is a reader's right answer to bad bytes, but only with the code it documents for them.
inline void expect_code(const Error& e, ErrorCode code, const std::string& reader) {
  if (e.code() != code) fail(reader + ": unexpected error code: " + e.what());
}

template <class T>
T load(const std::vector<std::uint8_t>& bytes, std::size_t at) {
  T v;
  std::memcpy(&v, bytes.data() + at, sizeof v);
  return v;
}

template <class T>
void store(std::vector<std::uint8_t>& bytes, std::size_t at, T v) {
  std::memcpy(bytes.data() + at, &v, sizeof v);
}

}  // namespace penumbra::fuzz

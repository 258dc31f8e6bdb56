// SPDX-License-Identifier: BSD-3-Clause
// tests/fuzz/standalone_main.cpp -- runs a libFuzzer harness without libFuzzer: every file named on
// the command line, and every file in each folder named (in name order; a missing folder is
// skipped), is passed to LLVMFuzzerTestOneInput once; no input at all is a failure. Ordinary
// builds link each harness with this and ctest runs it over its seeds and regression inputs, so
// a crash found by fuzzing stays fixed.
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

namespace fs = std::filesystem;

int main(int argc, char** argv) {
  std::vector<fs::path> inputs;
  for (int i = 1; i < argc; ++i) {
    const fs::path p(argv[i]);
    std::error_code ec;
    if (fs::is_directory(p, ec)) {
      std::vector<fs::path> files;
      for (const auto& e : fs::directory_iterator(p))
        if (e.is_regular_file()) files.push_back(e.path());
      std::sort(files.begin(), files.end());
      inputs.insert(inputs.end(), files.begin(), files.end());
    } else if (fs::exists(p, ec)) {
      inputs.push_back(p);
    } else {
      std::printf("%s: not there, skipped\n", argv[i]);
    }
  }
  for (const fs::path& p : inputs) {
    std::ifstream in(p, std::ios::binary);
    if (!in) {
      std::fprintf(stderr, "cannot read %s\n", p.c_str());
      return 2;
    }
    const std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::printf("%s (%zu bytes)\n", p.c_str(), bytes.size());
    std::fflush(stdout);  // a crash then names its input
    // A copy of exactly the input's size, as libFuzzer passes it: reading past it is caught. An
    // empty input gets a valid pointer too, as from libFuzzer.
    std::vector<std::uint8_t> data(bytes.begin(), bytes.end());
    static std::uint8_t none = 0;
    LLVMFuzzerTestOneInput(data.empty() ? &none : data.data(), data.size());
  }
  std::printf("%zu inputs ran\n", inputs.size());
  return inputs.empty() ? 1 : 0;  // no seeds: a wrong path, not a pass
}

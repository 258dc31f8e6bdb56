// SPDX-License-Identifier: BSD-3-Clause
// bench/render/bench_util.h -- timing and output helpers shared by the benchmark programs
#pragma once
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <fstream>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "penumbra/render/gpu_ray_caster.h"

namespace penumbra::bench {

/// Milliseconds elapsed since construction.
class Stopwatch {
public:
  double ms() const {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - m_start).count();
  }

private:
  std::chrono::steady_clock::time_point m_start = std::chrono::steady_clock::now();
};

/// Median of `values` (mean of the middle two for an even count); 0 for none.
inline double median(std::vector<double> values) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  return n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

/// `v` rounded to `digits` decimals, so JSON lines stay readable.
inline double rounded(double v, int digits = 3) {
  const double scale = std::pow(10.0, digits);
  return std::round(v * scale) / scale;
}

/// Value of command-line option `--name VALUE`, or `fallback` when absent.
inline std::string option(int argc, char** argv, const std::string& name, const std::string& fallback) {
  for (int i = 1; i + 1 < argc; ++i)
    if (argv[i] == "--" + name) return argv[i + 1];
  return fallback;
}



/// Difference of a rendered 8-bit RGB image from the reference.
struct ImageError {
  double rms_pct = 0;       ///< RMS over all pixels and channels, in % of 255
  int max_abs = 0;          ///< largest channel difference, in 8-bit levels
  std::size_t bad_pixels = 0;  ///< pixels with some channel off by more than 10% of 255
};

/// Compares equal-size RGB8 buffers.
inline ImageError compare_rgb8(const std::vector<unsigned char>& image, const std::vector<unsigned char>& reference) {
  ImageError e;
  double sum = 0;
  for (std::size_t p = 0; p + 2 < image.size() && p + 2 < reference.size(); p += 3) {
    int worst = 0;
    for (int c = 0; c < 3; ++c) {
      const int d = std::abs(static_cast<int>(image[p + c]) - static_cast<int>(reference[p + c]));
      sum += static_cast<double>(d) * d;
      worst = std::max(worst, d);
    }
    e.max_abs = std::max(e.max_abs, worst);
    if (worst > 25) ++e.bad_pixels;
  }
  if (!image.empty()) e.rms_pct = 100.0 * std::sqrt(sum / static_cast<double>(image.size())) / 255.0;
  return e;
}

/// The device for a benchmark's GPU lines, its log silenced; null, with the reason on stderr, when
/// the build has no GPU backend or no device opens (the CPU lines still run).
inline std::shared_ptr<render::GpuDevice> open_bench_gpu(const char* program) {
  if (!render::gpu_backend_compiled()) return nullptr;
  try {
    render::GpuOptions options;
    options.log = [](const std::string&) {};
    return render::GpuDevice::open(options);
  } catch (const std::exception& e) {
    std::cerr << program << ": no GPU lines: " << e.what() << "\n";
    return nullptr;
  }
}

}  // namespace penumbra::bench


namespace penumbra::bench {

/// One-minute load average of the machine (Linux), or -1 when unknown: timings taken while
/// other work runs are slower, and the JSON lines say so.
inline double load_average() {
  std::ifstream in("/proc/loadavg");
  double v = -1;
  if (!(in >> v)) return -1;
  return v;
}

/// A benchmark program's main: runs `run`, and turns an exception into one line on stderr
/// (prefixed by the program's name) and exit status 1.
inline int guarded_main(const char* program, int (*run)(int, char**), int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: %s\n", program, e.what());
    return 1;
  }
}

}  // namespace penumbra::bench

// SPDX-License-Identifier: BSD-3-Clause
// bench/compression/fields.cpp
#include "fields.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numeric>
#include <random>
#include <stdexcept>

#include "penumbra/core/morton.h"

namespace pnb_bench {

double Field::range() const {
  const auto [lo, hi] = std::minmax_element(values.begin(), values.end());
  return double(*hi) - double(*lo);
}

namespace {

struct P {
  double x, y, z;
};

std::vector<P> morton_points(std::uint64_t n) {
  std::mt19937_64 rng(2026);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<P> p(n);
  for (auto& q : p) q = {u(rng), u(rng), u(rng)};
  auto key = [](const P& q) {
    const auto s = [](double c) { return std::uint64_t(c * 2097151.0); };
    return penumbra::spread_bits_3d(s(q.x)) | penumbra::spread_bits_3d(s(q.y)) << 1 | penumbra::spread_bits_3d(s(q.z)) << 2;
  };
  std::sort(p.begin(), p.end(), [&](const P& a, const P& b) { return key(a) < key(b); });
  return p;
}

}  // namespace

Field synthetic_field(const std::string& kind, std::uint64_t n, std::uint32_t steps) {
  Field f;
  f.name = kind;
  f.vertices = n;
  f.steps = steps;
  f.times.resize(steps);
  f.values.resize(n * steps);
  const auto pts = morton_points(n);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(0, 1);
  for (std::uint32_t t = 0; t < steps; ++t) f.times[t] = 0.01 * t;
  if (kind == "smooth") {
    struct Blob {
      P c, v;
      double sigma, amp, phase;
    };
    std::vector<Blob> blobs(6);
    for (auto& b : blobs)
      b = {{u(rng), u(rng), u(rng)}, {u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5}, 0.12 + 0.08 * u(rng), 0.5 + u(rng),
           6.28 * u(rng)};
    for (std::uint32_t t = 0; t < steps; ++t) {
      const double s = double(t) / steps;
      for (std::uint64_t i = 0; i < n; ++i) {
        double val = 0;
        for (const auto& b : blobs) {
          const double dx = pts[i].x - (b.c.x + 0.6 * b.v.x * s), dy = pts[i].y - (b.c.y + 0.6 * b.v.y * s),
                       dz = pts[i].z - (b.c.z + 0.6 * b.v.z * s);
          const double amp = b.amp * (1 + 0.3 * std::sin(6.28 * s + b.phase));
          val += amp * std::exp(-(dx * dx + dy * dy + dz * dz) / (2 * b.sigma * b.sigma));
        }
        f.values[t * n + i] = float(val);
      }
    }
  } else if (kind == "shock") {
    // Blast-like planar front: constant-strength jump that weakens slowly as it travels, an
    // exponential relaxation behind it, and a state ahead that varies smoothly in space.
    const double nx = 0.95, ny = 0.25, nz = 0.19;
    for (std::uint32_t t = 0; t < steps; ++t) {
      const double s = double(t) / steps;
      const double front = -0.1 + 1.4 * s, strength = 1.5 / (1 + 0.8 * s);
      for (std::uint64_t i = 0; i < n; ++i) {
        const P& q = pts[i];
        const double d = q.x * nx + q.y * ny + q.z * nz;
        const double ahead = 1.0 + 0.2 * q.z + 0.1 * std::sin(4 * q.y);
        f.values[t * n + i] = float(d < front ? ahead + strength * std::exp(-(front - d) / 0.15) : ahead);
      }
    }
  } else if (kind == "shock-nonuniform") {
    const double nx = 0.95, ny = 0.25, nz = 0.19;  // front normal (about unit length)
    for (std::uint32_t t = 0; t < steps; ++t) {
      const double front = -0.1 + 1.4 * double(t) / steps;
      for (std::uint64_t i = 0; i < n; ++i) {
        const P& q = pts[i];
        const double d = q.x * nx + q.y * ny + q.z * nz;
        const double behind = 2.0 + 0.3 * std::sin(3 * q.y + 0.02 * t) * std::cos(2 * q.z);
        const double ahead = 1.0 + 0.2 * q.z;
        f.values[t * n + i] = float(d < front ? behind : ahead);
      }
    }
  } else if (kind == "eeg") {
    struct Source {
      P c;
      double period, phase, gain;
    };
    std::vector<Source> src(8);
    for (auto& s : src) s = {{u(rng), u(rng), u(rng)}, 8 + 5 * u(rng), 6.28 * u(rng), 0.5 + u(rng)};
    std::normal_distribution<float> noise(0.f, 1.f);
    for (std::uint32_t t = 0; t < steps; ++t)
      for (std::uint64_t i = 0; i < n; ++i) {
        double val = 0;
        for (const auto& s : src) {
          const double r2 = std::pow(pts[i].x - s.c.x, 2) + std::pow(pts[i].y - s.c.y, 2) + std::pow(pts[i].z - s.c.z, 2);
          val += s.gain * std::sin(6.28 * t / s.period + s.phase) / (r2 + 0.05);
        }
        f.values[t * n + i] = float(val);
      }
    // White noise at 30% of the signal's standard deviation.
    double sum = 0, sum2 = 0;
    for (float x : f.values) sum += x, sum2 += double(x) * x;
    const double sd = std::sqrt(std::max(0.0, sum2 / f.values.size() - std::pow(sum / f.values.size(), 2)));
    for (auto& x : f.values) x += float(0.3 * sd) * noise(rng);
  } else {
    throw std::runtime_error("unknown synthetic field '" + kind + "' (smooth, shock, eeg)");
  }
  return f;
}

Field load_raw_field(const std::string& path, const std::string& name) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("cannot open " + path);
  Field f;
  f.name = name;
  std::uint64_t n = 0, steps = 0;
  in.read(reinterpret_cast<char*>(&n), 8);
  in.read(reinterpret_cast<char*>(&steps), 8);
  if (!in || n == 0 || steps == 0 || n > (1ull << 32) || steps > (1u << 20)) throw std::runtime_error("bad header in " + path);
  f.vertices = n;
  f.steps = std::uint32_t(steps);
  f.times.resize(steps);
  f.values.resize(n * steps);
  in.read(reinterpret_cast<char*>(f.times.data()), std::streamsize(steps * 8));
  in.read(reinterpret_cast<char*>(f.values.data()), std::streamsize(n * steps * 4));
  if (!in) throw std::runtime_error(path + " is truncated");
  return f;
}

Field field_from_spec(const std::string& spec, std::uint64_t vertices, std::uint32_t steps) {
  if (spec.rfind("raw:", 0) != 0) return synthetic_field(spec, vertices, steps);
  // raw:PATH[:NAME]; without a name, the field is called after its file.
  const auto colon = spec.find(':', 4);
  const std::string path = spec.substr(4, colon == std::string::npos ? std::string::npos : colon - 4);
  return load_raw_field(path, colon == std::string::npos ? std::filesystem::path(path).stem().string() : spec.substr(colon + 1));
}

penumbra::compression::StreamingStats write_field_file(const Field& f, const std::string& path,
                                                       const penumbra::compression::CodecParams& codec) {
  penumbra::compression::StreamingOptions o;
  o.path = path;
  o.field_name = f.name;
  o.vertex_count = f.vertices;
  o.codec = codec;
  penumbra::compression::StreamingEncoder enc(o);
  for (std::uint32_t t = 0; t < f.steps; ++t) enc.push(f.times[t], f.values.data() + std::uint64_t(t) * f.vertices);
  enc.finish();
  return enc.stats();
}

}  // namespace pnb_bench

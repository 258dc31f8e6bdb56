// SPDX-License-Identifier: BSD-3-Clause
// bench/compression/decode_ab.cpp -- whole-window decode of one field by several builds of
// libpenumbra_compression.so in one process, round by round beside a memcpy of the same bytes;
// prints one JSON object per build.
//
// usage: pnb_decode_ab --field smooth|shock|shock-nonuniform|eeg|raw:PATH[:NAME] [--vertices N]
//                      [--steps T] [--bound REL] [--rounds R] [--same-blocks W1,W2,W3,W,T,LINEAR]
//                      LIBRARY...
//
// Runs of separate processes differ by 10-15 % on this kind of host (where the allocator and the
// kernel put the arrays decides how they share the caches), which hides the few per cent a
// kernel change is worth. Here every build decodes the same page into the same output in every
// round, in turns, and each line reports the median over rounds of the first build's time over
// its own: a paired ratio. Each build is opened with RTLD_DEEPBIND, so that its decode_window
// calls its own kernels; without it, the builds' internal calls bind to the first library loaded
// and every line times the same code. The builds must share this build's EncodedPage layout.
//
// --bound REL encodes with a range-relative bound (0, the default: plain VQ). --same-blocks gives
// every lane block of a predictive_lanes page the same widths (step 1, step 2, transient, later),
// transient end and extrapolating lanes, and no exception row: the decoded values are not the
// field's, but the time shows what the kernel's per-block control costs against its loop.
#include <dlfcn.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "fields.h"
#include "penumbra/compression/field_file.h"
#include "penumbra/compression/codec_params.h"
#include "penumbra/compression/window_codec.h"

using namespace pnb_bench;
namespace pc = penumbra::compression;
using Clock = std::chrono::steady_clock;

namespace {

double seconds(Clock::time_point a) { return std::chrono::duration<double>(Clock::now() - a).count(); }

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0 : v[v.size() / 2];
}

using DecodeWindow = void (*)(const pc::EncodedPage&, float*);

struct Build {
  std::string path;
  DecodeWindow decode = nullptr;
  std::vector<double> seconds;
};

// The same widths, transient end and extrapolating lanes in every block, no exception row.
bool make_blocks_alike(pc::EncodedPage& p, const std::string& spec) {
  unsigned w1, w2, w3, w, T, linear;
  if (std::sscanf(spec.c_str(), "%u,%u,%u,%u,%u,%i", &w1, &w2, &w3, &w, &T, &linear) != 6) return false;
  pc::LaneBlocks& L = p.lanes;
  const std::uint32_t n = p.step_count;
  if (L.empty() || n < 3 || T < 3 || T > n || std::max({w1, w2, w3, w}) > 32) return false;
  const std::uint64_t blocks = L.block_count();
  const std::uint64_t bits = p.quantiser.first_width + w1 + w2 + std::uint64_t(T - 3) * w3 + std::uint64_t(n - T) * w;
  for (std::uint64_t b = 0; b < blocks; ++b) {
    const std::uint8_t widths[5] = {std::uint8_t(w1), std::uint8_t(w2), std::uint8_t(w3), std::uint8_t(w), 0};
    std::copy(widths, widths + 5, L.widths.begin() + 5 * b);
    L.transient_ends[b] = std::uint8_t(T);
    L.linear[b] = std::uint16_t(linear);
    L.raw[b] = 0;
    L.exception_rows[b] = 0;
    L.bit_start[b] = b * bits;
    L.row_start[b] = L.high_start[b] = L.raw_start[b] = 0;
  }
  L.bit_start[blocks] = blocks * bits;
  L.row_start[blocks] = L.high_start[blocks] = L.raw_start[blocks] = 0;
  L.exception_steps.clear();
  L.exception_lanes.clear();
  L.highs.clear();
  L.raw_values.clear();
  // A zero row, the rows the blocks take, and the spare row past them (lane_blocks.h).
  L.words.resize(pc::LaneBlocks::kLanes * (1 + blocks * bits / 32 + 2));
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  std::string field_spec, same_blocks;
  std::uint64_t vertices = 100000;
  std::uint32_t steps = 128;
  double bound = 0;
  int rounds = 2001;
  std::vector<Build> builds;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const auto value = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "%s needs a value\n", a.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--field") field_spec = value();
    else if (a == "--vertices") vertices = std::stoull(value());
    else if (a == "--steps") steps = std::uint32_t(std::stoul(value()));
    else if (a == "--bound") bound = std::stod(value());
    else if (a == "--rounds") rounds = std::max(1, std::stoi(value()));
    else if (a == "--same-blocks") same_blocks = value();
    else builds.push_back(Build{a, nullptr, {}});
  }
  if (field_spec.empty() || builds.empty()) {
    std::fprintf(stderr, "usage: %s --field NAME|raw:PATH[:NAME] [--vertices N] [--steps T] [--bound REL] "
                         "[--rounds R] [--same-blocks W1,W2,W3,W,T,LINEAR] LIBRARY...\n", argv[0]);
    return 2;
  }
  for (Build& b : builds) {
    void* handle = dlopen(b.path.c_str(), RTLD_NOW | RTLD_LOCAL | RTLD_DEEPBIND);
    if (!handle) {
      std::fprintf(stderr, "%s\n", dlerror());
      return 1;
    }
    b.decode = reinterpret_cast<DecodeWindow>(dlsym(handle, "_ZN8penumbra11compression13decode_windowERKNS0_11EncodedPageEPf"));
    if (!b.decode) {
      std::fprintf(stderr, "%s: no decode_window\n", b.path.c_str());
      return 1;
    }
  }

  try {
    const Field f = field_from_spec(field_spec, vertices, steps);
    const std::string path = "/tmp/pnb_decode_ab_" + std::to_string(getpid()) + ".pnbf";
    pc::CodecParams codec;
    if (bound > 0) codec.bound = {pc::BoundKind::range_relative, bound};
    write_field_file(f, path, codec);
    const auto field = pc::CompressedField::open(path);
    std::vector<pc::EncodedPage> pages;
    for (std::size_t p = 0; p < field->page_count(); ++p) pages.push_back(*field->load_page(p));
    std::remove(path.c_str());
    if (!same_blocks.empty())
      for (pc::EncodedPage& p : pages)
        if (!make_blocks_alike(p, same_blocks)) {
          std::fprintf(stderr, "--same-blocks %s does not fit a page (predictive_lanes, 3 steps or more)\n", same_blocks.c_str());
          return 2;
        }

    Floats reference(f.values.size()), out(f.values.size()), copy(f.values.size());
    const auto decode_all = [&](DecodeWindow decode, float* to) {
      for (const pc::EncodedPage& p : pages) decode(p, to + std::uint64_t(p.first_step) * f.vertices);
    };
    decode_all(&pc::decode_window, reference.data());
    std::vector<double> copy_seconds;
    for (int r = 0; r < rounds; ++r) {
      auto t0 = Clock::now();
      std::memcpy(copy.data(), f.values.data(), copy.size() * 4);
      copy_seconds.push_back(seconds(t0));
      for (std::size_t k = 0; k < builds.size(); ++k) {
        Build& b = builds[(std::size_t(r) + k) % builds.size()];  // each build leads in turn
        t0 = Clock::now();
        decode_all(b.decode, out.data());
        b.seconds.push_back(seconds(t0));
      }
    }
    const double bytes = double(f.values.size()) * 4;
    for (Build& b : builds) {
      decode_all(b.decode, out.data());
      const bool identical = std::memcmp(out.data(), reference.data(), out.size() * 4) == 0;
      std::vector<double> vs_memcpy(rounds), vs_first(rounds);
      for (int r = 0; r < rounds; ++r) {
        vs_memcpy[r] = copy_seconds[r] / b.seconds[r];
        vs_first[r] = builds[0].seconds[r] / b.seconds[r];
      }
      std::printf("{\"bench\":\"decode_ab\",\"field\":\"%s\",\"bound_rel\":%g,\"same_blocks\":\"%s\",\"pages\":%zu,"
                  "\"library\":\"%s\",\"decode_us\":%.2f,\"decode_gbps\":%.1f,\"memcpy_gbps\":%.1f,"
                  "\"decode_vs_memcpy\":%.3f,\"speed_vs_first\":%.3f,\"identical_to_linked\":%s,\"rounds\":%d}\n",
                  f.name.c_str(), bound, same_blocks.c_str(), pages.size(), b.path.c_str(), median(b.seconds) * 1e6,
                  bytes / median(b.seconds) / 1e9, bytes / median(copy_seconds) / 1e9, median(vs_memcpy),
                  median(vs_first), identical ? "true" : "false", rounds);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pnb_decode_ab: %s\n", e.what());
    return 1;
  }
  return 0;
}

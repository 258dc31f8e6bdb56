// SPDX-License-Identifier: BSD-3-Clause
// bench/compression/compression_bench.cpp -- Penumbra's time-window VQ codec against ZFP,
// fpzip and temporal delta + zstd on one field; prints one JSON object per line.
//
// usage: pnb_bench_compression --field smooth|shock|eeg|raw:PATH[:NAME] [--vertices N] [--steps T]
//                              [--scratch DIR] [--no-peers]
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <functional>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#endif

#include "fields.h"
#include "peers.h"
#include "penumbra/compression/field_file.h"
#include "penumbra/compression/pager.h"
#include "penumbra/compression/streaming_encoder.h"
#include "penumbra/compression/window_codec.h"
#include "penumbra/core/thread_pool.h"

using namespace pnb_bench;
namespace pc = penumbra::compression;
using Clock = std::chrono::steady_clock;

namespace {

double seconds(Clock::time_point a) { return std::chrono::duration<double>(Clock::now() - a).count(); }

struct Quality {
  double psnr_db = 0, max_err_rel = 0;
};

Quality measure(const Field& f, const float* got) {
  const double range = f.range();
  double se = 0, mx = 0;
  for (std::size_t i = 0; i < f.values.size(); ++i) {
    const double d = std::fabs(double(f.values[i]) - got[i]);
    se += d * d;
    mx = std::max(mx, d);
  }
  const double mse = se / double(f.values.size());
  return {mse > 0 ? 10 * std::log10(range * range / mse) : 999.0, mx / range};
}

struct Row {
  std::string codec, param, match;
  double ratio = 0, encode_mbps = 0, decode_mbps = 0, step_mverts = 0;
  Quality q;
  std::string extra;  // additional "key":value pairs, comma-led
  double memcpy_gbps = 0;  // measured beside this row's decode; 0: the run's global figure
};

double g_memcpy_gbps = 0;

void print(const Field& f, const Row& r) {
  const double memcpy = r.memcpy_gbps > 0 ? r.memcpy_gbps : g_memcpy_gbps;
  std::printf(
      "{\"bench\":\"compression\",\"field\":\"%s\",\"vertices\":%llu,\"steps\":%u,\"codec\":\"%s\",\"param\":\"%s\","
      "\"match\":\"%s\",\"ratio\":%.2f,\"psnr_db\":%.2f,\"max_err_rel\":%.3g,\"encode_mbps\":%.1f,"
      "\"decode_mbps\":%.1f,\"step_mverts\":%.1f,\"memcpy_gbps\":%.2f,\"decode_vs_memcpy\":%.2f,\"threads\":%u%s}\n",
      f.name.c_str(), (unsigned long long)f.vertices, f.steps, r.codec.c_str(), r.param.c_str(), r.match.c_str(), r.ratio,
      r.q.psnr_db, r.q.max_err_rel, r.encode_mbps, r.decode_mbps, r.step_mverts, memcpy,
      r.decode_mbps / 1000.0 / memcpy, penumbra::worker_count(), r.extra.c_str());
  std::fflush(stdout);
}

// Timed rounds: at least `at_least`, and as many more as fit in 20 ms (at most 1000). Five rounds
// of mug's 317 KB take about 0.1 ms, which one busy moment of another process covers whole; on the
// 100K-vertex arrays five rounds already take longer than 20 ms.
bool another_round(int done, int at_least, Clock::time_point start) {
  return done < at_least || (seconds(start) < 0.02 && done < 1000);
}

double memcpy_gbps(const Field& f) {
  Floats dst(f.values.size());
  double best = 1e30;
  const auto start = Clock::now();
  for (int rep = 0; another_round(rep, 5, start); ++rep) {
    const auto t0 = Clock::now();
    std::memcpy(dst.data(), f.values.data(), f.values.size() * 4);
    best = std::min(best, seconds(t0));
  }
  volatile float sink = dst[dst.size() / 2];
  (void)sink;
  return double(f.values.size()) * 4 / best / 1e9;
}

// Evicts [p, p + bytes) from every cache level, so the next access comes from memory: the cold
// decode and memcpy below start as a replay does, with pages just read and a fresh output. Returns
// false where the instruction is not available (the cold keys are then left out).
bool evict(const void* p, std::size_t bytes) {
#if defined(__x86_64__) || defined(__i386__)
  const char* c = static_cast<const char*>(p);
  for (std::size_t i = 0; i < bytes; i += 64) _mm_clflush(c + i);
  _mm_mfence();
  return true;
#else
  (void)p, (void)bytes;
  return false;
#endif
}

template <class Vector>
bool evict(const Vector& v) {
  return evict(v.data(), v.size() * sizeof(v[0]));
}

bool evict(const pc::EncodedPage& p) {
  bool ok = evict(p.vq.c8) && evict(p.vq.cw) && evict(p.means.q) && evict(p.vq.i8) && evict(p.vq.iw);
  ok = ok && evict(p.aligned.ca) && evict(p.aligned.shift) && evict(p.aligned.ia);
  const pc::BitBlocks& b = p.blocks;
  ok = ok && evict(b.group_offsets) && evict(b.widths) && evict(b.payload) && evict(b.section_bits);
  const pc::LaneBlocks& l = p.lanes;
  ok = ok && evict(l.widths) && evict(l.linear) && evict(l.raw) && evict(l.exception_rows) && evict(l.exception_steps);
  ok = ok && evict(l.exception_lanes) && evict(l.exception_bits) && evict(l.raw_values) && evict(l.words);
  return ok && evict(l.bit_start) && evict(l.raw_start) && evict(l.row_start) && evict(l.high_start) && evict(l.highs);
}

// ---- Penumbra ----------------------------------------------------------------------------

Row run_penumbra(const Field& f, const std::string& scratch, pc::CodecParams params, const std::string& codec,
                 const std::string& param) {
  const double raw_mb = double(f.values.size()) * 4 / 1e6;
  const std::string path = scratch + "/" + f.name + "-" + codec + ".pnbf";
  const auto t0 = Clock::now();
  const pc::StreamingStats st = write_field_file(f, path, params);
  const double encode_s = seconds(t0);
  const auto field = pc::CompressedField::open(path);

  // Full decode, interleaved with memcpy of the same bytes so both see the same machine load
  // (the best of each over another_round's rounds): from resident pages (what a renderer holding
  // the page sees; peers also decode from memory), and from the file (page read + checksum + parse
  // included).
  Floats out(f.values.size()), copy(f.values.size());
  std::vector<std::shared_ptr<const pc::EncodedPage>> pages;
  for (std::size_t p = 0; p < field->page_count(); ++p) pages.push_back(field->load_page(p));
  double decode_s = 1e30, load_decode_s = 1e30, copy_s = 1e30;
  const auto rounds_start = Clock::now();
  for (int rep = 0; another_round(rep, 5, rounds_start); ++rep) {
    auto t1 = Clock::now();
    std::memcpy(copy.data(), f.values.data(), copy.size() * 4);
    copy_s = std::min(copy_s, seconds(t1));
    t1 = Clock::now();
    for (const auto& pg : pages) pc::decode_window(*pg, out.data() + pg->first_step * f.vertices);
    decode_s = std::min(decode_s, seconds(t1));
    t1 = Clock::now();
    for (std::size_t p = 0; p < field->page_count(); ++p)
      pc::decode_window(*field->load_page(p), out.data() + field->page(p).first_step * f.vertices);
    load_decode_s = std::min(load_decode_s, seconds(t1));
  }
  const double row_memcpy_gbps = double(copy.size()) * 4 / copy_s / 1e9;
  // The same two from memory (every input and output evicted before each), best of 5 each. An
  // array that fits in the caches (mug: 317 KB) is copied cache to cache above; here neither
  // side starts with its data at hand.
  double cold_decode_s = 1e30, cold_copy_s = 1e30;
  bool cold = true;
  for (int rep = 0; rep < 5 && cold; ++rep) {
    for (const auto& pg : pages) cold = cold && evict(*pg);
    cold = cold && evict(out);
    auto t1 = Clock::now();
    for (const auto& pg : pages) pc::decode_window(*pg, out.data() + pg->first_step * f.vertices);
    cold_decode_s = std::min(cold_decode_s, seconds(t1));
    cold = cold && evict(f.values) && evict(copy);
    t1 = Clock::now();
    std::memcpy(copy.data(), f.values.data(), copy.size() * 4);
    cold_copy_s = std::min(cold_copy_s, seconds(t1));
  }
  const Quality q = measure(f, out.data());

  // One step for all vertices: sequential playback through a new pager (its construction and
  // every page load included; pager_stalls counts reads that waited after prepare()), best of 3 like the other timings, so that one-off costs of the process (the
  // first read of the file, the first use of the worker threads) do not count.
  Floats step(f.vertices);
  double play_s = 1e30;
  pc::PagerStats ps;
  for (int rep = 0; rep < 3; ++rep) {
    const auto t2 = Clock::now();
    pc::Pager pager(field);
    pager.prepare(0);  // the first page's load: timed here, but set-up rather than a playback stall
    for (std::uint32_t t = 0; t < f.steps; ++t) pager.read_step(t, step.data());
    const double s = seconds(t2);
    if (s < play_s) play_s = s, ps = pager.stats();
  }
  // The same playback from resident pages (page reads and parsing left out): the decode of
  // one step by itself, best of 3.
  double resident_s = 1e30;
  for (int rep = 0; rep < 3; ++rep) {
    pc::StepCursor cursor;
    const auto t3 = Clock::now();
    for (const auto& pg : pages)
      for (std::uint32_t t = 0; t < pg->step_count; ++t) cursor.decode(pg, t, step.data());
    resident_s = std::min(resident_s, seconds(t3));
  }

  std::string methods;
  for (auto m : st.methods) methods += std::string(methods.empty() ? "" : ",") + pc::to_string(m);
  // Pages whose payload the file holds as a zstd frame: smaller on disk than once loaded (a
  // stored payload takes its 64-byte header and 16-byte coding prefix more).
  std::size_t zstd_pages = 0;
  for (std::size_t p = 0; p < field->page_count(); ++p)
    zstd_pages += field->page(p).bytes < field->page(p).payload_bytes + 80;
  std::ostringstream extra;
  extra << ",\"train_s_max\":" << st.max_train_seconds << ",\"decode_with_load_mbps\":" << raw_mb / load_decode_s
        << ",\"solver_waits\":" << st.solver_waits
        << ",\"pager_stalls\":" << ps.stalls << ",\"pager_recycled\":" << ps.recycled << ",\"pager_prepare_ms\":" << ps.prepare_seconds * 1e3
        << ",\"step_resident_mverts\":" << double(f.vertices) * f.steps / resident_s / 1e6 << ",\"pages\":\"" << methods << "\""
        << ",\"zstd_pages\":" << zstd_pages;
  if (cold)
    extra << ",\"cold_decode_mbps\":" << raw_mb / cold_decode_s << ",\"cold_memcpy_gbps\":" << raw_mb / cold_copy_s / 1e3
          << ",\"cold_decode_vs_memcpy\":" << cold_copy_s / cold_decode_s;
  Row r{codec, param, "", double(f.values.size()) * 4 / double(field->file_bytes()), raw_mb / encode_s,
        raw_mb / decode_s, double(f.vertices) * f.steps / play_s / 1e6, q, extra.str(), row_memcpy_gbps};
  std::filesystem::remove(path);
  return r;
}

// ---- Peers -------------------------------------------------------------------------------

struct Trial {
  double param = 0, ratio = 0;
  Quality q;
};

Trial trial(const Peer& peer, const Field& f, double param) {
  const auto bytes = peer.compress(f, param);
  Floats out(f.values.size());
  peer.decompress(bytes, f, param, out.data());
  return {param, double(f.values.size()) * 4 / double(bytes.size()), measure(f, out.data())};
}

// Most compressive parameter meeting `ok`; `looser` says which way of the bracket gives more
// compression. Log-space bisection over [lo, hi] (or integer bisection when `integer`).
Trial search(const Peer& peer, const Field& f, double lo, double hi, bool larger_is_looser, bool integer,
             const std::function<bool(const Quality&)>& ok, int iterations = 11) {
  Trial best{};
  bool found = false;
  double good = larger_is_looser ? lo : hi, bad = larger_is_looser ? hi : lo;
  const Trial at_good = trial(peer, f, good);
  if (!ok(at_good.q)) return at_good;  // even the tightest setting misses: report it
  best = at_good;
  found = true;
  for (int i = 0; i < iterations; ++i) {
    double mid = integer ? std::round((good + bad) / 2) : std::sqrt(good * bad);
    if (integer && (mid == good || mid == bad)) break;
    const Trial t = trial(peer, f, mid);
    if (ok(t.q)) {
      good = mid;
      if (!found || t.ratio > best.ratio) best = t;
    } else {
      bad = mid;
    }
  }
  return best;
}

Row time_peer(const Peer& peer, const Field& f, double param, const std::string& match) {
  const double raw_mb = double(f.values.size()) * 4 / 1e6;
  auto t0 = Clock::now();
  const auto bytes = peer.compress(f, param);
  const double enc = seconds(t0);
  Floats out(f.values.size());
  double dec = 1e30;
  const auto start = Clock::now();
  for (int rep = 0; another_round(rep, 2, start); ++rep) {
    t0 = Clock::now();
    peer.decompress(bytes, f, param, out.data());
    dec = std::min(dec, seconds(t0));
  }
  Floats step(f.vertices);
  const std::uint32_t probes = std::min<std::uint32_t>(f.steps, 4);
  t0 = Clock::now();
  for (std::uint32_t i = 0; i < probes; ++i) peer.decompress_step(bytes, f, param, (i * 37 + 5) % f.steps, step.data());
  const double step_s = seconds(t0) / probes;
  return {peer.name(), peer.describe(param, f.range()), match, double(f.values.size()) * 4 / double(bytes.size()),
          raw_mb / enc, raw_mb / dec, double(f.vertices) / step_s / 1e6, measure(f, out.data()), ""};
}

void run_peers(const Field& f, double target_psnr, double target_max_err_rel) {
  const double range = f.range();
  std::vector<std::unique_ptr<Peer>> peers;
  peers.push_back(make_zfp_accuracy());
  peers.push_back(make_zfp_rate());
  if (auto p = make_fpzip()) peers.push_back(std::move(p));
  peers.push_back(make_tdelta_zstd());
  const auto psnr_ok = [&](const Quality& q) { return q.psnr_db >= target_psnr; };
  const auto err_ok = [&](const Quality& q) { return q.max_err_rel <= target_max_err_rel; };
  std::ostringstream psnr_tag, err_tag;
  psnr_tag << "psnr>=" << std::round(target_psnr * 100) / 100;
  err_tag << "max_err_rel<=" << target_max_err_rel;
  for (const auto& peer : peers) {
    const std::string n = peer->name();
    std::cerr << "compression/" << f.name << ": matching " << n << "\n";
    for (int which = 0; which < 2; ++which) {
      const auto& ok = which == 0 ? std::function<bool(const Quality&)>(psnr_ok) : err_ok;
      Trial t;
      if (n == "zfp-accuracy") t = search(*peer, f, range * 1e-7, range, true, false, ok);
      else if (n == "zfp-rate") t = search(*peer, f, 0.25, 32, false, false, ok);
      else if (n == "fpzip") t = search(*peer, f, 2, 32, false, true, ok, 6);
      else t = search(*peer, f, range * 1e-8, range, true, false, ok);
      print(f, time_peer(*peer, f, t.param, which == 0 ? psnr_tag.str() : err_tag.str()));
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  std::string kind = "smooth", scratch = ".";
  std::uint64_t vertices = 100000;
  std::uint32_t steps = 128;
  bool peers = true;
  for (int i = 1; i < argc; ++i)
    if (std::string(argv[i]) == "--no-peers") {
      peers = false;
      for (int j = i; j + 1 < argc; ++j) argv[j] = argv[j + 1];
      --argc;
      break;
    }
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i], v = argv[i + 1];
    if (a == "--field") kind = v;
    else if (a == "--vertices") vertices = std::stoull(v);
    else if (a == "--steps") steps = std::uint32_t(std::stoul(v));
    else if (a == "--scratch") scratch = v;
    else {
      std::cerr << "unknown option " << a << "\n";
      return 2;
    }
  }
  try {
    const Field f = field_from_spec(kind, vertices, steps);
    std::filesystem::create_directories(scratch);
    g_memcpy_gbps = memcpy_gbps(f);
    std::cerr << "compression/" << f.name << ": " << f.vertices << " vertices x " << f.steps << " steps, range "
              << f.range() << "\n";

    pc::CodecParams vq;
    const Row plain = run_penumbra(f, scratch, vq, "penumbra-vq", "K=256,W=64");
    print(f, plain);
    for (double rel : {1e-2, 1e-3}) {
      pc::CodecParams b = vq;
      b.bound = {pc::BoundKind::range_relative, rel};
      std::ostringstream p;
      p << "K=256,W=64,bound_rel=" << rel;
      const Row r = run_penumbra(f, scratch, b, "penumbra-vq-bounded", p.str());
      print(f, r);
    }
    // Peers at equal PSNR (to penumbra-vq) and at equal max error (to the 1e-2 bound).
    if (peers) run_peers(f, plain.q.psnr_db, 1e-2);
  } catch (const std::exception& e) {
    std::cerr << "pnb_bench_compression: " << e.what() << "\n";
    return 1;
  }
  return 0;
}

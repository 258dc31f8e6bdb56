// SPDX-License-Identifier: BSD-3-Clause
// bench/compression/peers.cpp
#include "peers.h"

#include <zfp.h>
#include <zstd.h>
#ifdef PNB_HAVE_FPZIP
#include <fpzip.h>
#endif

#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>
#include <sstream>
#include <stdexcept>

namespace pnb_bench {

void Peer::decompress_step(const std::vector<std::uint8_t>& bytes, const Field& f, double param, std::uint32_t t,
                           float* out) const {
  std::vector<float> all(f.values.size());
  decompress(bytes, f, param, all.data());
  std::memcpy(out, all.data() + std::uint64_t(t) * f.vertices, f.vertices * 4);
}

namespace {

std::string fmt(const char* key, double v) {
  std::ostringstream s;
  s << key << "=" << v;
  return s.str();
}

class Zfp : public Peer {
public:
  explicit Zfp(bool fixed_rate) : m_rate(fixed_rate) {}
  std::string name() const override { return m_rate ? "zfp-rate" : "zfp-accuracy"; }
  std::string describe(double p, double range) const override {
    return m_rate ? fmt("bits_per_value", p) : fmt("tolerance_rel", p / range);
  }

  zfp_stream* open_stream(double param) const {
    zfp_stream* z = zfp_stream_open(nullptr);
    if (m_rate)
      zfp_stream_set_rate(z, param, zfp_type_float, 2, zfp_true);  // block-aligned: random access
    else
      zfp_stream_set_accuracy(z, param);
    return z;
  }

  std::vector<std::uint8_t> compress(const Field& f, double param) const override {
    zfp_field* field = zfp_field_2d(const_cast<float*>(f.values.data()), zfp_type_float, f.vertices, f.steps);
    zfp_stream* z = open_stream(param);
    // Compression on all cores when the library has OpenMP (decompression is serial in 1.0).
    zfp_stream_set_execution(z, zfp_exec_omp);
    std::vector<std::uint8_t> buf(zfp_stream_maximum_size(z, field));
    bitstream* bs = stream_open(buf.data(), buf.size());
    zfp_stream_set_bit_stream(z, bs);
    zfp_stream_rewind(z);
    const size_t size = zfp_compress(z, field);
    stream_close(bs);
    zfp_stream_close(z);
    zfp_field_free(field);
    if (!size) throw std::runtime_error("zfp_compress failed");
    buf.resize(size);
    return buf;
  }

  void decompress(const std::vector<std::uint8_t>& bytes, const Field& f, double param, float* out) const override {
    zfp_field* field = zfp_field_2d(out, zfp_type_float, f.vertices, f.steps);
    zfp_stream* z = open_stream(param);
    bitstream* bs = stream_open(const_cast<std::uint8_t*>(bytes.data()), bytes.size());
    zfp_stream_set_bit_stream(z, bs);
    zfp_stream_rewind(z);
    const size_t ok = zfp_decompress(z, field);
    stream_close(bs);
    zfp_stream_close(z);
    zfp_field_free(field);
    if (!ok) throw std::runtime_error("zfp_decompress failed");
  }

  void decompress_step(const std::vector<std::uint8_t>& bytes, const Field& f, double param, std::uint32_t t,
                       float* out) const override {
    if (!m_rate || f.vertices % 4 || f.steps % 4) return Peer::decompress_step(bytes, f, param, t, out);
    // Fixed rate: every 4x4 block takes maxbits, so the slab of 4 steps holding t is found by
    // arithmetic and decoded alone.
    zfp_stream* z = open_stream(param);
    bitstream* bs = stream_open(const_cast<std::uint8_t*>(bytes.data()), bytes.size());
    zfp_stream_set_bit_stream(z, bs);
    zfp_stream_rewind(z);
    const std::uint64_t bx = f.vertices / 4, slab = t / 4;
    stream_rseek(bs, bitstream_offset(slab * bx * z->maxbits));
    float block[16];
    const std::uint32_t row = t % 4;
    for (std::uint64_t b = 0; b < bx; ++b) {
      zfp_decode_block_float_2(z, block);
      std::memcpy(out + b * 4, block + row * 4, 16);
    }
    stream_close(bs);
    zfp_stream_close(z);
  }

private:
  bool m_rate;
};

#ifdef PNB_HAVE_FPZIP
class Fpzip : public Peer {
public:
  std::string name() const override { return "fpzip"; }
  std::string describe(double p, double) const override { return fmt("precision_bits", p); }
  std::vector<std::uint8_t> compress(const Field& f, double param) const override {
    std::vector<std::uint8_t> buf(f.values.size() * 4 + 1024);
    FPZ* fpz = fpzip_write_to_buffer(buf.data(), buf.size());
    fpz->type = FPZIP_TYPE_FLOAT;
    fpz->prec = int(param);
    fpz->nx = int(f.vertices);
    fpz->ny = int(f.steps);
    fpz->nz = 1;
    fpz->nf = 1;
    const size_t size = fpzip_write_header(fpz) ? fpzip_write(fpz, f.values.data()) : 0;
    fpzip_write_close(fpz);
    if (!size) throw std::runtime_error("fpzip_write failed");
    buf.resize(size);
    return buf;
  }
  void decompress(const std::vector<std::uint8_t>& bytes, const Field&, double, float* out) const override {
    FPZ* fpz = fpzip_read_from_buffer(bytes.data());
    const size_t ok = fpzip_read_header(fpz) ? fpzip_read(fpz, out) : 0;
    fpzip_read_close(fpz);
    if (!ok) throw std::runtime_error("fpzip_read failed");
  }
};
#endif

class TdeltaZstd : public Peer {
public:
  std::string name() const override { return "tdelta-zstd"; }
  std::string describe(double p, double range) const override { return fmt("bound_rel", p / range); }

  std::vector<std::uint8_t> compress(const Field& f, double bound) const override {
    const float lo = *std::min_element(f.values.begin(), f.values.end());
    const double step = 2 * bound;
    const std::uint64_t n = f.vertices;
    std::vector<std::int32_t> d(f.values.size());
    std::vector<std::int64_t> previous(n, 0);
    std::int64_t widest = 0;
    for (std::uint32_t t = 0; t < f.steps; ++t)
      for (std::uint64_t v = 0; v < n; ++v) {
        const std::int64_t k = std::llround((double(f.values[t * n + v]) - lo) / step);
        d[t * n + v] = std::int32_t(k - previous[v]);
        widest = std::max<std::int64_t>(widest, std::llabs(k - previous[v]));
        previous[v] = k;
      }
    // Narrow deltas go to zstd as 16-bit integers.
    const bool narrow = widest < 32768;
    std::vector<std::uint8_t> raw;
    if (narrow) {
      std::vector<std::int16_t> s(d.begin(), d.end());
      raw.assign(reinterpret_cast<std::uint8_t*>(s.data()), reinterpret_cast<std::uint8_t*>(s.data() + s.size()));
    } else {
      raw.assign(reinterpret_cast<std::uint8_t*>(d.data()), reinterpret_cast<std::uint8_t*>(d.data() + d.size()));
    }
    std::vector<std::uint8_t> out(ZSTD_compressBound(raw.size()) + 8);
    std::memcpy(out.data(), &lo, 4);
    out[4] = narrow;
    const size_t size = ZSTD_compress(out.data() + 8, out.size() - 8, raw.data(), raw.size(), 3);
    if (ZSTD_isError(size)) throw std::runtime_error("ZSTD_compress failed");
    out.resize(size + 8);
    return out;
  }

  void decompress(const std::vector<std::uint8_t>& bytes, const Field& f, double bound, float* out) const override {
    float lo;
    std::memcpy(&lo, bytes.data(), 4);
    const bool narrow = bytes[4];
    const std::uint64_t n = f.vertices, count = n * f.steps;
    std::vector<std::uint8_t> raw(count * (narrow ? 2 : 4));
    const size_t got = ZSTD_decompress(raw.data(), raw.size(), bytes.data() + 8, bytes.size() - 8);
    if (ZSTD_isError(got) || got != raw.size()) throw std::runtime_error("ZSTD_decompress failed");
    const float step = float(2 * bound);
    std::vector<std::int64_t> k(n, 0);
    for (std::uint32_t t = 0; t < f.steps; ++t)
      for (std::uint64_t v = 0; v < n; ++v) {
        const std::uint64_t i = t * n + v;
        if (narrow) {
          std::int16_t s;
          std::memcpy(&s, raw.data() + 2 * i, 2);
          k[v] += s;
        } else {
          std::int32_t s;
          std::memcpy(&s, raw.data() + 4 * i, 4);
          k[v] += s;
        }
        out[i] = lo + float(double(k[v]) * step);
      }
  }
};

}  // namespace

std::unique_ptr<Peer> make_zfp_accuracy() { return std::make_unique<Zfp>(false); }
std::unique_ptr<Peer> make_zfp_rate() { return std::make_unique<Zfp>(true); }
std::unique_ptr<Peer> make_fpzip() {
#ifdef PNB_HAVE_FPZIP
  return std::make_unique<Fpzip>();
#else
  return nullptr;
#endif
}
std::unique_ptr<Peer> make_tdelta_zstd() { return std::make_unique<TdeltaZstd>(); }

}  // namespace pnb_bench

// SPDX-License-Identifier: BSD-3-Clause
// bench/compression/peers.h -- the peer codecs, each on the [time x vertex] float array.
#pragma once
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "fields.h"

namespace pnb_bench {

/// One lossy peer at one parameter: compress the whole array, decompress it, and (where the
/// codec allows it) decompress one time step alone.
class Peer {
public:
  virtual ~Peer() = default;
  virtual std::string name() const = 0;
  virtual std::vector<std::uint8_t> compress(const Field& f, double param) const = 0;
  virtual void decompress(const std::vector<std::uint8_t>& bytes, const Field& f, double param, float* out) const = 0;
  /// Decodes step t for all vertices; the default decodes everything and copies the step.
  virtual void decompress_step(const std::vector<std::uint8_t>& bytes, const Field& f, double param, std::uint32_t t,
                               float* out) const;
  /// What `param` means, for the JSON line.
  virtual std::string describe(double param, double range) const = 0;
};

/// ZFP 1.0 fixed-accuracy (param: absolute tolerance), 2D field nx = vertices, ny = steps.
std::unique_ptr<Peer> make_zfp_accuracy();
/// ZFP 1.0 fixed-rate (param: bits per value), block-aligned so one 4-step slab decodes alone.
std::unique_ptr<Peer> make_zfp_rate();
/// fpzip (param: bits of precision kept, 2..32); nullptr when built without fpzip.
std::unique_ptr<Peer> make_fpzip();
/// Uniform quantisation with step 2 x bound (param: absolute bound), per-vertex temporal
/// delta, zstd level 3.
std::unique_ptr<Peer> make_tdelta_zstd();

}  // namespace pnb_bench

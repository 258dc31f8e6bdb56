// SPDX-License-Identifier: BSD-3-Clause
// tests/unit/compression/stream_field.h -- writing a synthetic field to a file the way a solver
// does: one push per step through the streaming encoder.
#pragma once
#include <cstdint>
#include <string>

#include "penumbra/compression/streaming_encoder.h"
#include "test_fields.h"

namespace penumbra::compression::testing {

/// Streams `f` into the field file `path` named `name`; returns the encoder's statistics.
inline StreamingStats stream_field(const SyntheticField& f, const std::string& path, const CodecParams& codec,
                                   const std::string& name, std::uint64_t memory_budget_bytes = 0) {
  StreamingOptions o;
  o.path = path;
  o.field_name = name;
  o.vertex_count = f.vertices;
  o.codec = codec;
  o.memory_budget_bytes = memory_budget_bytes;
  StreamingEncoder enc(o);
  for (std::uint32_t t = 0; t < f.steps; ++t) enc.push(f.times[t], f.values.data() + std::uint64_t(t) * f.vertices);
  enc.finish();
  return enc.stats();
}

}  // namespace penumbra::compression::testing

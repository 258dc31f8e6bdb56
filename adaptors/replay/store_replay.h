// SPDX-License-Identifier: BSD-3-Clause
// adaptors/replay/store_replay.h -- penumbra-replay over a run's compressed history
#pragma once
#include <cstddef>
#include <iosfwd>
#include <string>
#include <utility>

namespace penumbra::replay {

/// True when `path` is a store segment (a directory holding mesh.pnbm), or a store directory
/// (holding segment-NNN folders).
bool is_store(const std::string& path);

/// Renders the steps [first, last) of the stored run at `path` (a segment, or a store directory:
/// then every segment in order, --steps counting through them) with `config` through the C API,
/// exactly as if the solver ran again: each segment's mesh as a topology of its own, moved to
/// each step's stored coordinates where its points moved, the stored fields (decoded from their
/// windows, paged), the stored times and cycles. `steps` is the --steps text ("a:b"), empty for all; a bad one
/// throws UsageError. Returns the exit status (0 success, 1 a failure, reported on `err`).
int replay_store(const std::string& config, const std::string& path, const std::string& steps, bool quiet,
                 std::ostream& out, std::ostream& err);

}  // namespace penumbra::replay

// SPDX-License-Identifier: BSD-3-Clause
// adaptors/replay/store_replay.h -- penumbra-replay over a run's compressed history
#pragma once
#include <cstddef>
#include <functional>
#include <iosfwd>
#include <string>
#include <utility>

#include "penumbra/penumbra.h"

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

/// The same over ranks (penumbra-replay-mpi): `create` makes the context (pnb_create_mpi on the
/// communicator), and rank `rank` of `ranks` replays its share of every segment's cells
/// (StorePiece), whatever rank count wrote the store. A segment written over ranks is replayed
/// whole by one process. Where a later segment begins at a cycle an earlier one already holds (a
/// run restarted from a checkpoint), the earlier one's steps from that cycle on are left out.
/// `out` is written by rank 0 only.
struct ReplayRanks {
  int rank = 0, ranks = 1;
  std::function<pnb_status(const char* config, pnb_context* ctx)> create;
};
int replay_store(const std::string& config, const std::string& path, const std::string& steps, bool quiet,
                 std::ostream& out, std::ostream& err, const ReplayRanks& ranks);

}  // namespace penumbra::replay

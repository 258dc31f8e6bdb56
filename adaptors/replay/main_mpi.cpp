// SPDX-License-Identifier: BSD-3-Clause
// adaptors/replay/main_mpi.cpp -- penumbra-replay-mpi CONFIG STORE [--steps a:b] [--quiet], under mpirun
//
// Re-renders a run's compressed history over the ranks of MPI_COMM_WORLD, whatever rank count
// wrote it: each rank publishes its share of every segment's cells (StorePiece) and the ranks
// composite one database, as the run itself did (pnb_create_mpi).
#include <mpi.h>

#include <iostream>
#include <string>
#include <vector>

#include "penumbra/penumbra_mpi.h"
#include "step_range.h"
#include "store_replay.h"

namespace {

const char* const kUsage =
    "usage: mpirun -np N penumbra-replay-mpi CONFIG STORE [--steps a:b] [--quiet]\n"
    "  Replays a run's compressed history (a store directory, config \"store\", or one of its\n"
    "  segment-NNN folders) over N ranks, whatever rank count wrote it; rank r renders the r-th\n"
    "  N-th of every segment's cells. Exit status: 0 ok, 1 read/render failure, 2 usage error.\n";

int replay(const std::vector<std::string>& args, int rank, int ranks) {
  std::string config, store, steps;
  bool quiet = false;
  for (std::size_t i = 0; i < args.size(); ++i) {
    if (args[i] == "--quiet") {
      quiet = true;
    } else if (args[i] == "--steps" && i + 1 < args.size()) {
      steps = args[++i];
    } else if (config.empty()) {
      config = args[i];
    } else if (store.empty()) {
      store = args[i];
    } else {
      throw penumbra::replay::UsageError("unexpected argument '" + args[i] + "'");
    }
  }
  if (store.empty()) throw penumbra::replay::UsageError("CONFIG and STORE are required");
  if (!penumbra::replay::is_store(store)) throw penumbra::replay::UsageError("'" + store + "' is not a store");
  penumbra::replay::ReplayRanks over{rank, ranks, [](const char* c, pnb_context* ctx) {
                                       return pnb_create_mpi(c, MPI_COMM_WORLD, ctx);
                                     }};
  return penumbra::replay::replay_store(config, store, steps, quiet, std::cout, std::cerr, over);
}

}  // namespace

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  int rank = 0, ranks = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &ranks);
  int status = 0;
  try {
    status = replay(std::vector<std::string>(argv + 1, argv + argc), rank, ranks);
  } catch (const penumbra::replay::UsageError& e) {
    if (rank == 0) std::cerr << "penumbra-replay-mpi: " << e.what() << "\n" << kUsage;
    status = 2;
  }
  int worst = 0;
  MPI_Allreduce(&status, &worst, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
  MPI_Finalize();
  return worst;
}

// SPDX-License-Identifier: BSD-3-Clause
// tests/mpi/mpi_exchange_test.cpp -- the ranks' exchanges (RankGroup::exchange, over
// sparse_alltoallv) deliver every message whole and in place, whichever pairs have none.
//
// Usage (under mpirun -np N): penumbra_mpi_exchange_test
// Rank r sends rank d (r + 2 d) % 4 values (none for a quarter of the pairs, itself included),
// each naming r, d and its index; then a round where only rank 0 sends, to the last rank, and
// one where nobody sends. Exits 0 on every rank when every rank received exactly what was sent.
#include <mpi.h>

#include <cstdio>
#include <vector>

#include "mpi_rank_group.h"

namespace {

double value(int from, int to, std::size_t i) { return 10000.0 * from + 100.0 * to + static_cast<double>(i); }

// One round: `count(from, to)` values from each rank to each; whether this rank got what it should.
template <class Count>
bool round_trips(penumbra::insitu::MpiRankGroup& group, Count count, const char* what) {
  const int rank = group.rank(), ranks = group.size();
  std::vector<std::vector<double>> to_each(static_cast<std::size_t>(ranks));
  for (int d = 0; d < ranks; ++d)
    for (std::size_t i = 0; i < count(rank, d); ++i) to_each[static_cast<std::size_t>(d)].push_back(value(rank, d, i));
  const auto from_each = group.exchange(to_each);
  bool good = from_each.size() == static_cast<std::size_t>(ranks);
  for (int s = 0; good && s < ranks; ++s) {
    const auto& got = from_each[static_cast<std::size_t>(s)];
    good = got.size() == count(s, rank);
    for (std::size_t i = 0; good && i < got.size(); ++i) good = got[i] == value(s, rank, i);
    if (!good) std::fprintf(stderr, "rank %d, %s: wrong message from rank %d (%zu values)\n", rank, what, s, got.size());
  }
  return good;
}

}  // namespace

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  int good = 1;
  {
    penumbra::insitu::MpiRankGroup group(MPI_COMM_WORLD);
    const int last = group.size() - 1;
    good = round_trips(group, [](int from, int to) { return static_cast<std::size_t>((from + 2 * to) % 4); }, "irregular") ? good : 0;
    good = round_trips(group, [last](int from, int to) { return std::size_t{from == 0 && to == last ? 5u : 0u}; }, "one pair") ? good : 0;
    good = round_trips(group, [](int, int) { return std::size_t{0}; }, "none") ? good : 0;
  }
  int all = 0;
  MPI_Allreduce(&good, &all, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
  MPI_Finalize();
  return all ? 0 : 1;
}

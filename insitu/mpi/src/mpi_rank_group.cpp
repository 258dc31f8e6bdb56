// SPDX-License-Identifier: BSD-3-Clause
// insitu/mpi/src/mpi_rank_group.cpp -- agreements and reductions over an MPI communicator
#include "mpi_rank_group.h"

#include <string>
#include <vector>

#include "penumbra/core/error.h"
#include "run_compositing.h"

namespace penumbra::insitu {

void check_mpi(int status, const char* what) {
  if (status == MPI_SUCCESS) return;
  char text[MPI_MAX_ERROR_STRING];
  int length = 0;
  MPI_Error_string(status, text, &length);
  throw Error(ErrorCode::internal_error, std::string(what) + " failed: " + std::string(text, static_cast<std::size_t>(length)));
}

MpiRankGroup::MpiRankGroup(MPI_Comm comm) {
  int initialized = 0, finalized = 0;
  MPI_Initialized(&initialized);
  MPI_Finalized(&finalized);
  if (!initialized || finalized)
    throw Error(ErrorCode::invalid_operation, "pnb_create_mpi: MPI is not initialised (call MPI_Init first) or already finalized");
  check_mpi(MPI_Comm_dup(comm, &m_comm), "pnb_create_mpi: MPI_Comm_dup");
  MPI_Comm_rank(m_comm, &m_rank);
  MPI_Comm_size(m_comm, &m_size);
}

MpiRankGroup::~MpiRankGroup() {
  int finalized = 0;
  MPI_Finalized(&finalized);
  if (!finalized && m_comm != MPI_COMM_NULL) MPI_Comm_free(&m_comm);
}

std::vector<RankGroup::Failure> MpiRankGroup::failures(int code, const std::string& message) {
  const int mine[2] = {code, code != 0 ? static_cast<int>(message.size()) : 0};
  std::vector<int> all(2 * static_cast<std::size_t>(m_size));
  check_mpi(MPI_Allgather(mine, 2, MPI_INT, all.data(), 2, MPI_INT, m_comm), "MPI_Allgather of the ranks' status");
  std::vector<int> lengths(static_cast<std::size_t>(m_size)), offsets(static_cast<std::size_t>(m_size));
  int total = 0;
  for (int r = 0; r < m_size; ++r) {
    lengths[static_cast<std::size_t>(r)] = all[2 * static_cast<std::size_t>(r) + 1];
    offsets[static_cast<std::size_t>(r)] = total;
    total += lengths[static_cast<std::size_t>(r)];
  }
  std::vector<Failure> failed;
  if (total == 0 && std::all_of(all.begin(), all.end(), [](int v) { return v == 0; })) return failed;
  std::string text(static_cast<std::size_t>(total), '\0');
  check_mpi(MPI_Allgatherv(message.data(), mine[1], MPI_CHAR, text.data(), lengths.data(), offsets.data(), MPI_CHAR, m_comm),
            "MPI_Allgatherv of the ranks' messages");
  for (int r = 0; r < m_size; ++r) {
    const int c = all[2 * static_cast<std::size_t>(r)];
    if (c != 0)
      failed.push_back({r, c, text.substr(static_cast<std::size_t>(offsets[static_cast<std::size_t>(r)]),
                                          static_cast<std::size_t>(lengths[static_cast<std::size_t>(r)]))});
  }
  return failed;
}

void MpiRankGroup::minimum(double* values, int count) {
  check_mpi(MPI_Allreduce(MPI_IN_PLACE, values, count, MPI_DOUBLE, MPI_MIN, m_comm), "MPI_Allreduce");
}

render::Image MpiRankGroup::composite(const render::RayRuns& runs, int width, int height) {
  return composite_runs(m_comm, runs, width, height);
}

}  // namespace penumbra::insitu

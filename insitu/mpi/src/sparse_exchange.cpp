// SPDX-License-Identifier: BSD-3-Clause
// insitu/mpi/src/sparse_exchange.cpp -- an all-to-all exchange whose empty messages are never sent
#include "sparse_exchange.h"

#include <vector>

#include "mpi_rank_group.h"

namespace penumbra::insitu {

void sparse_alltoallv(const void* send, const int* send_counts, const int* send_offsets, void* receive,
                      const int* receive_counts, const int* receive_offsets, MPI_Datatype type, MPI_Comm comm, int tag) {
  int ranks = 1;
  MPI_Comm_size(comm, &ranks);
  MPI_Aint lower = 0, extent = 0;
  check_mpi(MPI_Type_get_extent(type, &lower, &extent), "MPI_Type_get_extent");
  std::vector<MPI_Request> requests;  // handles: values that MPI_Waitall reads wherever they lie
  // Receives first, so that a send finds its receive posted.
  for (int r = 0; r < ranks; ++r) {
    if (receive_counts[r] == 0) continue;
    char* at = static_cast<char*>(receive) + static_cast<MPI_Aint>(receive_offsets[r]) * extent;
    check_mpi(MPI_Irecv(at, receive_counts[r], type, r, tag, comm, &requests.emplace_back()), "MPI_Irecv");
  }
  for (int r = 0; r < ranks; ++r) {
    if (send_counts[r] == 0) continue;
    const char* at = static_cast<const char*>(send) + static_cast<MPI_Aint>(send_offsets[r]) * extent;
    check_mpi(MPI_Isend(at, send_counts[r], type, r, tag, comm, &requests.emplace_back()), "MPI_Isend");
  }
  check_mpi(MPI_Waitall(static_cast<int>(requests.size()), requests.data(), MPI_STATUSES_IGNORE), "MPI_Waitall");
}

}  // namespace penumbra::insitu

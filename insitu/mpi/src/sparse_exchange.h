// SPDX-License-Identifier: BSD-3-Clause
// insitu/mpi/src/sparse_exchange.h -- an all-to-all exchange whose empty messages are never sent
#pragma once
#include <mpi.h>

namespace penumbra::insitu {

/// MPI_Alltoallv's exchange, with the counts already known on both sides (as after an
/// MPI_Alltoall of them): a receive is posted for each rank that sends this one something and a
/// send for each rank this one sends something, and nothing for the others. MPI's own
/// Alltoallv (OpenMPI's linear one among them) posts one message per pair, empty or not: P − 1
/// per rank per call, the latency that limits direct send at thousands of ranks, where a compact
/// part's runs reach about P^(2/3) bands. Every rank of `comm` calls it with the same `tag`;
/// another exchange on `comm` starts only after this one returns. Throws Error(internal_error)
/// when an MPI call fails.
void sparse_alltoallv(const void* send, const int* send_counts, const int* send_offsets, void* receive,
                      const int* receive_counts, const int* receive_offsets, MPI_Datatype type, MPI_Comm comm, int tag);

}  // namespace penumbra::insitu

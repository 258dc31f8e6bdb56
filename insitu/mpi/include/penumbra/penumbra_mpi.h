/* SPDX-License-Identifier: BSD-3-Clause */
/* insitu/mpi/include/penumbra/penumbra_mpi.h -- Penumbra over the ranks of an MPI communicator.
 *
 * Link Penumbra::mpi (libpenumbra_mpi) instead of Penumbra::insitu: it holds every function of
 * penumbra.h and these. Each rank publishes its own partition: its cells and the points they use
 * (points on partition boundaries appear on every rank that uses them), its fields on those
 * points or cells. A rank that holds none of the rendered region publishes a mesh with
 * point_count, connectivity_count and cell_types_count 0 (and fields of count 0): it renders,
 * lights and stores nothing of its own and takes part in every agreement. Each rank ray casts its
 * own cells; the runs where each ray is inside a rank's cells are exchanged by image region
 * through MPI, merged in depth order and composited, so the picture is that of the whole mesh
 * rendered in one process, whatever the partition. Rank 0 writes the image database.
 *
 * Collective (every rank of the communicator calls them, in the same order): pnb_create_mpi,
 * pnb_publish_mesh, pnb_execute and pnb_destroy. A failure on any rank (a wrong count, NaN, a
 * failed write, an index out of range, a time or cycle that differs from rank 0's) is returned by
 * every rank's call, its message naming the rank, and no rank is left waiting. pnb_publish_field,
 * pnb_step_needs, pnb_last_step, pnb_last_error and pnb_finalize are local: pnb_finalize flushes
 * this rank's store, and a write that fails there is this rank's status alone (call it on every
 * rank and agree on the outcome, e.g. with MPI_Allreduce, before acting on it).
 * With "async" each rank's worker thread communicates through a duplicate of `comm` (a step's
 * failure is then every rank's status at the next pnb_execute that renders or stores, or at
 * pnb_finalize: the same call on every rank); that needs
 * MPI initialised at MPI_THREAD_MULTIPLE (MPI_Init_thread), and below it every step runs inside
 * pnb_execute, which rank 0 says once on stderr. Not over several ranks (refused at creation,
 * naming the key): lighting.occlusion.space "image" with shadows. */
#ifndef PENUMBRA_MPI_H
#define PENUMBRA_MPI_H

#include <mpi.h>

#include "penumbra/core/export.h"
#include "penumbra/penumbra.h"

PNB_PUBLIC_BEGIN

#ifdef __cplusplus
extern "C" {
#endif

/* pnb_create on the ranks of `comm` (MPI initialised by the caller; Penumbra works on its own
 * duplicate of the communicator, so its messages never meet the solver's). */
pnb_status pnb_create_mpi(const char* config, MPI_Comm comm, pnb_context* out);
/* The same with a Fortran communicator handle (MPI_Fint, converted with MPI_Comm_f2c). */
pnb_status pnb_create_mpi_f(const char* config, MPI_Fint comm, pnb_context* out);

#ifdef __cplusplus
}
#endif

PNB_PUBLIC_END

#endif /* PENUMBRA_MPI_H */

// SPDX-License-Identifier: BSD-3-Clause
// insitu/mpi/src/c_api_mpi.cpp -- pnb_create_mpi: a context over an MPI communicator's ranks
#include <memory>
#include <string>

#include "c_api_internal.h"
#include "mpi_rank_group.h"
#include "penumbra/core/error.h"
#include "penumbra/penumbra_mpi.h"

extern "C" {

pnb_status pnb_create_mpi(const char* config, MPI_Comm comm, pnb_context* out) {
  if (out) *out = nullptr;
  std::shared_ptr<penumbra::insitu::RankGroup> group;
  try {
    group = std::make_shared<penumbra::insitu::MpiRankGroup>(comm);
  } catch (const penumbra::Error& e) {
    return penumbra::insitu::creation_failed(static_cast<pnb_status>(e.code()), e.what());
  }
  return penumbra::insitu::create_context("pnb_create_mpi", config, std::move(group), out);
}

pnb_status pnb_create_mpi_f(const char* config, MPI_Fint comm, pnb_context* out) {
  return pnb_create_mpi(config, MPI_Comm_f2c(comm), out);
}

}  // extern "C"

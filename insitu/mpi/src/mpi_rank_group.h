// SPDX-License-Identifier: BSD-3-Clause
// insitu/mpi/src/mpi_rank_group.h -- the ranks of an MPI communicator as a Context's RankGroup
#pragma once
#include <mpi.h>

#include "rank_group.h"

namespace penumbra::insitu {

/// A RankGroup over its own duplicate of a communicator (MPI_Comm_dup: collective), so that its
/// messages never meet the solver's. Freed (collectively) with the group, unless MPI was
/// finalized first.
class MpiRankGroup final : public RankGroup {
public:
  /// Throws Error(invalid_operation) when MPI is not initialised, Error(internal_error) when an
  /// MPI call fails.
  explicit MpiRankGroup(MPI_Comm comm);
  ~MpiRankGroup() override;
  MpiRankGroup(const MpiRankGroup&) = delete;
  MpiRankGroup& operator=(const MpiRankGroup&) = delete;

  int rank() const override { return m_rank; }
  int size() const override { return m_size; }
  std::vector<Failure> failures(int code, const std::string& message) override;
  void minimum(double* values, int count) override;
  void maximum(float* values, std::size_t count) override;
  void maximum(std::uint8_t* values, std::size_t count) override;
  std::vector<double> all_gather(const std::vector<double>& mine) override;
  std::vector<std::vector<double>> exchange(const std::vector<std::vector<double>>& to_each) override;
  render::Image composite(const render::RayRuns& runs, int width, int height) override;
  std::shared_ptr<RankGroup> duplicate() override;
  std::string threads_refused() const override;

private:
  MPI_Comm m_comm = MPI_COMM_NULL;
  int m_rank = 0, m_size = 1;
};

/// Throws Error(internal_error) naming `what` unless `status` is MPI_SUCCESS.
void check_mpi(int status, const char* what);

}  // namespace penumbra::insitu

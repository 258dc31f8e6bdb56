// SPDX-License-Identifier: BSD-3-Clause
// insitu/mpi/src/mpi_rank_group.cpp -- agreements and reductions over an MPI communicator
#include "mpi_rank_group.h"

#include <algorithm>
#include <cstdint>
#include <string>
#include <vector>

#include "penumbra/core/error.h"
#include "run_compositing.h"
#include "sparse_exchange.h"

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

std::shared_ptr<RankGroup> MpiRankGroup::duplicate() { return std::make_shared<MpiRankGroup>(m_comm); }

std::string MpiRankGroup::threads_refused() const {
  int provided = MPI_THREAD_SINGLE;
  MPI_Query_thread(&provided);
  switch (provided) {
    case MPI_THREAD_MULTIPLE: return {};
    case MPI_THREAD_SERIALIZED: return "MPI_THREAD_SERIALIZED";
    case MPI_THREAD_FUNNELED: return "MPI_THREAD_FUNNELED";
    default: return "MPI_THREAD_SINGLE";
  }
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

namespace {

// MPI counts are ints: long arrays are reduced in pieces.
constexpr std::size_t kPiece = std::size_t{1} << 30;

void allreduce_max(MPI_Comm comm, void* values, std::size_t count, MPI_Datatype type, std::size_t size) {
  auto* bytes = static_cast<unsigned char*>(values);
  for (std::size_t done = 0; done < count; done += kPiece) {
    const int n = static_cast<int>(std::min(kPiece, count - done));
    check_mpi(MPI_Allreduce(MPI_IN_PLACE, bytes + done * size, n, type, MPI_MAX, comm), "MPI_Allreduce (maximum)");
  }
}

}  // namespace

void MpiRankGroup::maximum(float* values, std::size_t count) {
  allreduce_max(m_comm, values, count, MPI_FLOAT, sizeof(float));
}

void MpiRankGroup::maximum(std::uint8_t* values, std::size_t count) {
  allreduce_max(m_comm, values, count, MPI_UINT8_T, 1);
}

std::vector<double> MpiRankGroup::all_gather(const std::vector<double>& mine) {
  std::vector<double> all(mine.size() * static_cast<std::size_t>(m_size));
  check_mpi(MPI_Allgather(mine.data(), static_cast<int>(mine.size()), MPI_DOUBLE, all.data(), static_cast<int>(mine.size()),
                          MPI_DOUBLE, m_comm),
            "MPI_Allgather");
  return all;
}

std::vector<std::vector<double>> MpiRankGroup::exchange(const std::vector<std::vector<double>>& to_each) {
  const auto ranks = static_cast<std::size_t>(m_size);
  if (to_each.size() != ranks)
    throw Error(ErrorCode::internal_error, "RankGroup::exchange: " + std::to_string(to_each.size()) + " messages for " +
                                               std::to_string(ranks) + " ranks");
  std::size_t sending = 0;
  for (const auto& m : to_each) sending += m.size();
  // Agreed before any exchange, so that a rank over MPI's int counts stops every rank, not itself.
  int oversize = sending > static_cast<std::size_t>(INT32_MAX) ? 1 : 0;
  check_mpi(MPI_Allreduce(MPI_IN_PLACE, &oversize, 1, MPI_INT, MPI_MAX, m_comm), "MPI_Allreduce");
  if (oversize != 0)
    throw Error(ErrorCode::out_of_memory, "RankGroup::exchange: a rank has more than 2^31 values to send");
  std::vector<int> send_counts(ranks), send_offsets(ranks), recv_counts(ranks), recv_offsets(ranks);
  std::vector<double> sent;
  sent.reserve(sending);
  for (std::size_t r = 0; r < ranks; ++r) {
    send_offsets[r] = static_cast<int>(sent.size());
    send_counts[r] = static_cast<int>(to_each[r].size());
    sent.insert(sent.end(), to_each[r].begin(), to_each[r].end());
  }
  check_mpi(MPI_Alltoall(send_counts.data(), 1, MPI_INT, recv_counts.data(), 1, MPI_INT, m_comm), "MPI_Alltoall of the counts");
  std::size_t total = 0;
  for (std::size_t r = 0; r < ranks; ++r) total += static_cast<std::size_t>(recv_counts[r]);
  oversize = total > static_cast<std::size_t>(INT32_MAX) ? 1 : 0;
  check_mpi(MPI_Allreduce(MPI_IN_PLACE, &oversize, 1, MPI_INT, MPI_MAX, m_comm), "MPI_Allreduce");
  if (oversize != 0)
    throw Error(ErrorCode::out_of_memory, "RankGroup::exchange: a rank would receive more than 2^31 values");
  for (std::size_t r = 0, at = 0; r < ranks; at += static_cast<std::size_t>(recv_counts[r]), ++r)
    recv_offsets[r] = static_cast<int>(at);
  std::vector<double> received(total);
  // Ranks exchange with the few that share their points, not with every rank.
  constexpr int kExchangeTag = 7103;
  sparse_alltoallv(sent.data(), send_counts.data(), send_offsets.data(), received.data(), recv_counts.data(), recv_offsets.data(),
                   MPI_DOUBLE, m_comm, kExchangeTag);
  std::vector<std::vector<double>> from_each(ranks);
  for (std::size_t r = 0; r < ranks; ++r)
    from_each[r].assign(received.begin() + recv_offsets[r], received.begin() + recv_offsets[r] + recv_counts[r]);
  return from_each;
}

render::Image MpiRankGroup::composite(const render::RayRuns& runs, int width, int height) {
  return composite_runs(m_comm, runs, width, height);
}

}  // namespace penumbra::insitu

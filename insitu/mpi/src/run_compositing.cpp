// SPDX-License-Identifier: BSD-3-Clause
// insitu/mpi/src/run_compositing.cpp -- direct-send compositing of ray runs by image bands
#include "run_compositing.h"

#include <algorithm>
#include <cstdint>
#include <vector>

#include "mpi_rank_group.h"
#include "penumbra/core/error.h"
#include "sparse_exchange.h"

namespace penumbra::insitu {
namespace {

// Tags of the point-to-point messages of one composite, on the group's own communicator.
constexpr int kPairsTag = 7101, kRunsTag = 7102;

// The first pixel of band `b` of `ranks` bands of whole rows.
std::size_t band_begin(int b, int ranks, int width, int height) {
  return static_cast<std::size_t>(static_cast<long long>(height) * b / ranks) * static_cast<std::size_t>(width);
}

int to_count(std::size_t n, const char* what) {
  if (n > static_cast<std::size_t>(INT32_MAX))
    throw Error(ErrorCode::out_of_memory, std::string("compositing: ") + what + " exceed an MPI count (2^31 - 1)");
  return static_cast<int>(n);
}

// A RayRun as MPI sees it: six floats.
struct RunType {
  MPI_Datatype type = MPI_DATATYPE_NULL;
  RunType() {
    static_assert(sizeof(render::RayRun) == 6 * sizeof(float));
    check_mpi(MPI_Type_contiguous(6, MPI_FLOAT, &type), "MPI_Type_contiguous");
    check_mpi(MPI_Type_commit(&type), "MPI_Type_commit");
  }
  ~RunType() { MPI_Type_free(&type); }
};

}  // namespace

void composite_in_order(const render::RayRun* runs, std::size_t count, float rgba[4]) {
  double rgb[3] = {0, 0, 0}, transmittance = 1;
  for (std::size_t i = 0; i < count; ++i) {
    for (int c = 0; c < 3; ++c) rgb[c] += transmittance * runs[i].rgba[c];
    transmittance *= 1.0 - runs[i].rgba[3];
  }
  for (int c = 0; c < 3; ++c) rgba[c] = static_cast<float>(rgb[c]);
  rgba[3] = static_cast<float>(1.0 - transmittance);
}

void composite_pixel(std::vector<render::RayRun>& runs, float rgba[4]) {
  std::sort(runs.begin(), runs.end(), [](const render::RayRun& a, const render::RayRun& b) {
    return a.entry_depth != b.entry_depth ? a.entry_depth < b.entry_depth : a.exit_depth < b.exit_depth;
  });
  composite_in_order(runs.data(), runs.size(), rgba);
}

render::Image composite_runs(MPI_Comm comm, const render::RayRuns& runs, int width, int height) {
  int rank = 0, size = 1;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &size);
  const auto ranks = static_cast<std::size_t>(size);
  auto first_run = [&](std::size_t pixel) { return runs.empty() ? std::size_t{0} : static_cast<std::size_t>(runs.offsets[pixel]); };

  // Per destination band: the pixels that have runs, as (pixel within the band, runs) pairs in
  // pixel order (a pixel no ray of this rank's cells reaches costs nothing), and the runs.
  std::vector<std::uint32_t> pairs;
  std::vector<int> send(2 * ranks), send_pairs(ranks), pairs_at(ranks), send_runs(ranks), send_at(ranks);
  std::vector<int> band_pixels(ranks), pixel_at(ranks);
  for (int b = 0; b < size; ++b) {
    const std::size_t p0 = band_begin(b, size, width, height), p1 = band_begin(b + 1, size, width, height);
    const auto bi = static_cast<std::size_t>(b);
    band_pixels[bi] = to_count(p1 - p0, "a band's pixels");
    pixel_at[bi] = to_count(p0, "the image's pixels");
    pairs_at[bi] = to_count(pairs.size(), "the covered pixels");
    for (std::size_t p = p0; p < p1 && !runs.empty(); ++p)
      if (const std::uint32_t n = runs.offsets[p + 1] - runs.offsets[p]; n > 0) pairs.insert(pairs.end(), {static_cast<std::uint32_t>(p - p0), n});
    send_pairs[bi] = to_count(pairs.size() - static_cast<std::size_t>(pairs_at[bi]), "the covered pixels");
    send_runs[bi] = to_count(first_run(p1) - first_run(p0), "a band's runs");
    send_at[bi] = to_count(first_run(p0), "a view's runs");
    send[2 * bi] = send_pairs[bi];
    send[2 * bi + 1] = send_runs[bi];
  }
  const std::size_t mine0 = band_begin(rank, size, width, height), mine1 = band_begin(rank + 1, size, width, height);

  // What each rank sends here; then the pairs and the runs themselves.
  std::vector<int> got_sizes(2 * ranks);
  check_mpi(MPI_Alltoall(send.data(), 2, MPI_INT, got_sizes.data(), 2, MPI_INT, comm), "MPI_Alltoall of run counts");
  std::vector<int> recv_pairs(ranks), recv_pairs_at(ranks), recv_runs(ranks), recv_at(ranks);
  std::size_t total_pairs = 0, total_runs = 0;
  for (std::size_t s = 0; s < ranks; ++s) {
    recv_pairs[s] = got_sizes[2 * s];
    recv_runs[s] = got_sizes[2 * s + 1];
    recv_pairs_at[s] = to_count(total_pairs, "the received pixels");
    recv_at[s] = to_count(total_runs, "the received runs");
    total_pairs += static_cast<std::size_t>(recv_pairs[s]);
    total_runs += static_cast<std::size_t>(recv_runs[s]);
  }
  // Only to and from the ranks whose bands this rank's runs reach, and that reach its band.
  std::vector<std::uint32_t> got_pairs(total_pairs);
  sparse_alltoallv(pairs.data(), send_pairs.data(), pairs_at.data(), got_pairs.data(), recv_pairs.data(), recv_pairs_at.data(),
                   MPI_UINT32_T, comm, kPairsTag);
  std::vector<render::RayRun> got(total_runs);
  const RunType run_type;
  sparse_alltoallv(runs.runs.data(), send_runs.data(), send_at.data(), got.data(), recv_runs.data(), recv_at.data(), run_type.type,
                   comm, kRunsTag);

  // This rank's band: each pixel's runs from every rank, in depth order, composited. A pixel whose
  // runs all come from one rank takes them as they are (a rank's runs are front to back already);
  // only pixels that several ranks cover are sorted.
  std::vector<float> band(4 * (mine1 - mine0));
  std::vector<std::size_t> run_at(recv_at.begin(), recv_at.end()), pair_at(recv_pairs_at.begin(), recv_pairs_at.end());
  std::vector<std::uint32_t> here(ranks);  // runs of each source at the current pixel
  std::vector<render::RayRun> pixel;
  for (std::size_t p = 0; p < mine1 - mine0; ++p) {
    int sources = 0, only = 0;
    for (std::size_t s = 0; s < ranks; ++s) {
      const std::size_t end = static_cast<std::size_t>(recv_pairs_at[s] + recv_pairs[s]);
      here[s] = pair_at[s] < end && got_pairs[pair_at[s]] == p ? got_pairs[pair_at[s] + 1] : 0;
      if (here[s] > 0) {
        pair_at[s] += 2;
        ++sources;
        only = static_cast<int>(s);
      }
    }
    if (sources <= 1) {
      std::size_t& at = run_at[static_cast<std::size_t>(only)];
      composite_in_order(got.data() + at, here[static_cast<std::size_t>(only)], &band[4 * p]);
      at += here[static_cast<std::size_t>(only)];
      continue;
    }
    pixel.clear();
    for (std::size_t s = 0; s < ranks; ++s) {
      pixel.insert(pixel.end(), got.begin() + static_cast<std::ptrdiff_t>(run_at[s]),
                   got.begin() + static_cast<std::ptrdiff_t>(run_at[s] + here[s]));
      run_at[s] += here[s];
    }
    composite_pixel(pixel, &band[4 * p]);
  }

  // The bands to rank 0, in row order.
  render::Image image;
  std::vector<int> band_floats(static_cast<std::size_t>(size)), band_at(static_cast<std::size_t>(size));
  for (int b = 0; b < size; ++b) {
    band_floats[static_cast<std::size_t>(b)] = to_count(4 * static_cast<std::size_t>(band_pixels[static_cast<std::size_t>(b)]), "a band's values");
    band_at[static_cast<std::size_t>(b)] = to_count(4 * static_cast<std::size_t>(pixel_at[static_cast<std::size_t>(b)]), "the image's values");
  }
  if (rank == 0) image = render::Image(width, height);
  check_mpi(MPI_Gatherv(band.data(), to_count(band.size(), "a band's values"), MPI_FLOAT, rank == 0 ? image.rgba.data() : nullptr,
                        band_floats.data(), band_at.data(), MPI_FLOAT, 0, comm),
            "MPI_Gatherv of the image bands");
  return image;
}

}  // namespace penumbra::insitu

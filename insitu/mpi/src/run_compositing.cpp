// SPDX-License-Identifier: BSD-3-Clause
// insitu/mpi/src/run_compositing.cpp -- direct-send compositing of ray runs by image bands
#include "run_compositing.h"

#include <algorithm>
#include <cstdint>
#include <vector>

#include "mpi_rank_group.h"
#include "penumbra/core/error.h"

namespace penumbra::insitu {
namespace {

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
  const std::size_t pixels = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  // Runs per pixel, and where each band's runs start.
  std::vector<std::uint32_t> counts(pixels, 0);
  if (!runs.empty())
    for (std::size_t p = 0; p < pixels; ++p) counts[p] = runs.offsets[p + 1] - runs.offsets[p];
  auto first_run = [&](std::size_t pixel) { return runs.empty() ? std::size_t{0} : static_cast<std::size_t>(runs.offsets[pixel]); };

  std::vector<int> send_runs(static_cast<std::size_t>(size)), send_at(static_cast<std::size_t>(size));
  std::vector<int> send_pixels(static_cast<std::size_t>(size)), pixel_at(static_cast<std::size_t>(size));
  for (int b = 0; b < size; ++b) {
    const std::size_t p0 = band_begin(b, size, width, height), p1 = band_begin(b + 1, size, width, height);
    send_pixels[static_cast<std::size_t>(b)] = to_count(p1 - p0, "a band's pixels");
    pixel_at[static_cast<std::size_t>(b)] = to_count(p0, "the image's pixels");
    send_runs[static_cast<std::size_t>(b)] = to_count(first_run(p1) - first_run(p0), "a band's runs");
    send_at[static_cast<std::size_t>(b)] = to_count(first_run(p0), "a view's runs");
  }
  const std::size_t mine0 = band_begin(rank, size, width, height), mine1 = band_begin(rank + 1, size, width, height);
  const int band_pixels = to_count(mine1 - mine0, "a band's pixels");

  // How many runs each rank sends here; then the counts per pixel and the runs themselves.
  std::vector<int> recv_runs(static_cast<std::size_t>(size));
  check_mpi(MPI_Alltoall(send_runs.data(), 1, MPI_INT, recv_runs.data(), 1, MPI_INT, comm), "MPI_Alltoall of run counts");
  std::vector<int> recv_pixels(static_cast<std::size_t>(size), band_pixels), recv_pixel_at(static_cast<std::size_t>(size));
  std::vector<int> recv_at(static_cast<std::size_t>(size));
  std::size_t total = 0;
  for (int s = 0; s < size; ++s) {
    recv_pixel_at[static_cast<std::size_t>(s)] = to_count(static_cast<std::size_t>(s) * (mine1 - mine0), "the received counts");
    recv_at[static_cast<std::size_t>(s)] = to_count(total, "the received runs");
    total += static_cast<std::size_t>(recv_runs[static_cast<std::size_t>(s)]);
  }
  std::vector<std::uint32_t> got_counts(static_cast<std::size_t>(size) * (mine1 - mine0));
  check_mpi(MPI_Alltoallv(counts.data(), send_pixels.data(), pixel_at.data(), MPI_UINT32_T, got_counts.data(),
                          recv_pixels.data(), recv_pixel_at.data(), MPI_UINT32_T, comm),
            "MPI_Alltoallv of runs per pixel");
  std::vector<render::RayRun> got(total);
  const RunType run_type;
  check_mpi(MPI_Alltoallv(runs.runs.data(), send_runs.data(), send_at.data(), run_type.type, got.data(), recv_runs.data(),
                          recv_at.data(), run_type.type, comm),
            "MPI_Alltoallv of runs");

  // This rank's band: each pixel's runs from every rank, in depth order, composited. A pixel whose
  // runs all come from one rank takes them as they are (a rank's runs are front to back already);
  // only pixels that several ranks cover are sorted.
  std::vector<float> band(4 * (mine1 - mine0));
  std::vector<std::size_t> cursor(recv_at.begin(), recv_at.end());
  std::vector<render::RayRun> pixel;
  for (std::size_t p = 0; p < mine1 - mine0; ++p) {
    pixel.clear();
    int sources = 0, only = 0;
    for (int s = 0; s < size; ++s)
      if (got_counts[static_cast<std::size_t>(s) * (mine1 - mine0) + p] > 0) ++sources, only = s;
    if (sources <= 1) {
      const std::uint32_t n = got_counts[static_cast<std::size_t>(only) * (mine1 - mine0) + p];
      std::size_t& at = cursor[static_cast<std::size_t>(only)];
      composite_in_order(&got[at], n, &band[4 * p]);
      at += n;
      continue;
    }
    for (int s = 0; s < size; ++s) {
      const std::uint32_t n = got_counts[static_cast<std::size_t>(s) * (mine1 - mine0) + p];
      std::size_t& at = cursor[static_cast<std::size_t>(s)];
      pixel.insert(pixel.end(), got.begin() + static_cast<std::ptrdiff_t>(at), got.begin() + static_cast<std::ptrdiff_t>(at + n));
      at += n;
    }
    composite_pixel(pixel, &band[4 * p]);
  }

  // The bands to rank 0, in row order.
  render::Image image;
  std::vector<int> band_floats(static_cast<std::size_t>(size)), band_at(static_cast<std::size_t>(size));
  for (int b = 0; b < size; ++b) {
    band_floats[static_cast<std::size_t>(b)] = to_count(4 * static_cast<std::size_t>(send_pixels[static_cast<std::size_t>(b)]), "a band's values");
    band_at[static_cast<std::size_t>(b)] = to_count(4 * static_cast<std::size_t>(pixel_at[static_cast<std::size_t>(b)]), "the image's values");
  }
  if (rank == 0) image = render::Image(width, height);
  check_mpi(MPI_Gatherv(band.data(), to_count(band.size(), "a band's values"), MPI_FLOAT, rank == 0 ? image.rgba.data() : nullptr,
                        band_floats.data(), band_at.data(), MPI_FLOAT, 0, comm),
            "MPI_Gatherv of the image bands");
  return image;
}

}  // namespace penumbra::insitu

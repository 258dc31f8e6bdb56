// SPDX-License-Identifier: BSD-3-Clause
// tests/mpi/mpi_failure_test.cpp -- one rank of three goes wrong; every rank's status says so,
// naming that rank, and no rank is left waiting in a collective.
//
// Usage (under mpirun -np 3): penumbra_mpi_failure_test OUT_DIR KIND
//   KIND  nan    rank 1's field holds a NaN at step 0, with a store (which keeps only finite
//                values): every rank's pnb_execute of step 0 fails naming rank 1; step 1 renders
//         index  rank 1's mesh names a point past its points (the library throws inside): every
//                rank's pnb_publish_mesh fails naming rank 1; the good mesh then renders
//         empty  rank 1's mesh descriptor is refused before its contents are read (point_count
//                0): every rank's pnb_publish_mesh fails naming rank 1 (none goes on alone into
//                the call's collectives); the good mesh then renders
//         time   rank 1 passes another time (100) for step 0: every rank's pnb_execute fails
//                naming rank 1 (the ranks disagree on the step); with "every_time": 1, steps 1
//                and 2 then render on every rank (the refused step left the time rule as it was)
//         write  rank 1's files may not grow past 4 KiB (RLIMIT_FSIZE, as a full disk): its store's
//                writes fail; every rank's first failing call is the same one and names rank 1,
//                the steps before it are in rank 0's database, and every later call returns
//         cycle  rank 1 passes a cycle one above the others', past 2^53 (where doubles skip odd
//                integers): every rank's pnb_execute fails naming rank 1 and its exact cycle
//         async  with "async" (MPI_THREAD_MULTIPLE) and no store: rank 1 publishes no field at
//                step 0, so the workers' step fails; steps at times 0, 0.5, 1, 1.5, 2 under
//                "every_time": 1: the failure is every rank's status at the same call, the next
//                step that renders (time 1), not at the step between (0.5) on the ranks whose
//                workers finished sooner (rank 0 waits 0.3 s before it); step 4 renders
// Each rank is killed by SIGALRM after 60 s (a hang fails the test before ctest's timeout does).
// Exits 0 on every rank when every expectation holds on every rank, else 1.
#include <mpi.h>
#include <signal.h>
#include <sys/resource.h>
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include "fixtures/meshes.h"
#include "mpi_partition.h"
#include "penumbra/penumbra_mpi.h"

namespace {

namespace fs = std::filesystem;
using penumbra::fixtures::OwnedMesh;
using penumbra::mpi_test::field_at;

constexpr int kFaultyRank = 1;

std::string config(const std::string& out, bool async) {
  const std::string keeps = async ? R"("async": true)" : R"("store": {"directory": ")" + out + R"(/store", "window": 8})";
  return R"({"output": {"directory": ")" + out + R"(/db"},
      "image": {"width": 64, "height": 48}, "cameras": {"phi": [30], "theta": [20]},
      "fields": [{"name": "T", "range": [-2, 3],
                  "transfer_function": {"colors": [[0, 0.1, 0.2, 0.9], [1, 1, 0.2, 0.1]], "opacities": [[0, 1], [1, 10]]}}],
      "trigger": {"every_time": 1}, )" + keeps + "}";
}

// What one call returned on this rank: its status and, on failure, the message.
struct Outcome {
  pnb_status status = PNB_OK;
  std::string message;
};

Outcome outcome(pnb_context ctx, pnb_status s) { return {s, s == PNB_OK ? "" : pnb_last_error(ctx)}; }

bool names_faulty_rank(const Outcome& o) { return o.message.find("rank " + std::to_string(kFaultyRank)) != std::string::npos; }

// Whether this rank's outcome of a call that must fail everywhere does, naming the faulty rank.
bool failed_naming_it(const Outcome& o, const char* what, int rank) {
  const bool good = o.status != PNB_OK && names_faulty_rank(o);
  if (!good) std::fprintf(stderr, "rank %d: %s should fail naming rank %d, got %d: %s\n", rank, what, kFaultyRank, static_cast<int>(o.status), o.message.c_str());
  if (good && rank == 0) std::printf("%s: %s\n", what, o.message.c_str());
  return good;
}

bool succeeded(const Outcome& o, const char* what, int rank) {
  if (o.status != PNB_OK) std::fprintf(stderr, "rank %d: %s: %s\n", rank, what, o.message.c_str());
  return o.status == PNB_OK;
}

// Whether the step of `cycle` succeeded and rendered: it is every rank's last rendered step, and
// rank 0 (which writes the images) counts them.
bool rendered(pnb_context ctx, const Outcome& o, std::int64_t cycle, int rank) {
  pnb_step_stats stats = PNB_STEP_STATS_INIT;
  const bool good = succeeded(o, "a step after the failure", rank) && pnb_last_step(ctx, &stats) == PNB_OK &&
                    stats.cycle == cycle && (rank != 0 || stats.images > 0);
  if (!good) std::fprintf(stderr, "rank %d: cycle %lld did not render (last rendered: cycle %lld, %d images)\n", rank,
                          static_cast<long long>(cycle), static_cast<long long>(stats.cycle), static_cast<int>(stats.images));
  return good;
}

Outcome step(pnb_context ctx, const OwnedMesh& mesh, std::int64_t cycle, double time, bool with_nan) {
  const int phase = static_cast<int>(cycle % 16);
  auto values = penumbra::fixtures::sample(mesh, [phase](double x, double y, double z) { return field_at(x, y, z, phase); });
  if (with_nan) values[values.size() / 2] = std::numeric_limits<double>::quiet_NaN();
  pnb_field_desc f = PNB_FIELD_DESC_INIT;
  f.name = "T", f.values = values.data(), f.count = static_cast<int64_t>(values.size());
  const Outcome published = outcome(ctx, pnb_publish_field(ctx, &f, PNB_COPY));
  if (published.status != PNB_OK) return published;
  return outcome(ctx, pnb_execute(ctx, time, cycle));
}

bool publish(pnb_context ctx, const OwnedMesh& mesh, int rank) {
  const pnb_mesh_desc m = penumbra::mpi_test::mesh_desc(mesh);
  return succeeded(outcome(ctx, pnb_publish_mesh(ctx, &m, PNB_COPY)), "pnb_publish_mesh", rank);
}

bool nan_field(pnb_context ctx, const OwnedMesh& mesh, int rank) {
  bool good = publish(ctx, mesh, rank);
  good = failed_naming_it(step(ctx, mesh, 0, 0, rank == kFaultyRank), "step 0 (a NaN on rank 1)", rank) && good;
  return rendered(ctx, step(ctx, mesh, 1, 1, false), 1, rank) && good;
}

bool bad_index(pnb_context ctx, const OwnedMesh& mesh, int rank) {
  OwnedMesh broken = mesh;
  if (rank == kFaultyRank) broken.connectivity[broken.connectivity.size() / 2] = static_cast<int64_t>(mesh.point_count()) + 5;
  const pnb_mesh_desc m = penumbra::mpi_test::mesh_desc(broken);
  bool good = failed_naming_it(outcome(ctx, pnb_publish_mesh(ctx, &m, PNB_COPY)), "pnb_publish_mesh (an index out of range on rank 1)", rank);
  good = publish(ctx, mesh, rank) && good;
  return rendered(ctx, step(ctx, mesh, 0, 0, false), 0, rank) && good;
}

bool refused_descriptor(pnb_context ctx, const OwnedMesh& mesh, int rank) {
  pnb_mesh_desc m = penumbra::mpi_test::mesh_desc(mesh);
  if (rank == kFaultyRank) m.point_count = 0;
  bool good = failed_naming_it(outcome(ctx, pnb_publish_mesh(ctx, &m, PNB_COPY)), "pnb_publish_mesh (point_count 0 on rank 1)", rank);
  good = publish(ctx, mesh, rank) && good;
  return rendered(ctx, step(ctx, mesh, 0, 0, false), 0, rank) && good;
}

bool other_cycle(pnb_context ctx, const OwnedMesh& mesh, int rank) {
  constexpr std::int64_t kBig = (std::int64_t{1} << 53) + 4;
  bool good = publish(ctx, mesh, rank);
  const Outcome o = step(ctx, mesh, rank == kFaultyRank ? kBig + 1 : kBig, 0, false);
  good = failed_naming_it(o, "a step past 2^53 (another cycle on rank 1)", rank) && good;
  if (o.message.find("rank 1 passed time 0, cycle " + std::to_string(kBig + 1)) == std::string::npos) {
    std::fprintf(stderr, "rank %d: the message does not give rank 1's exact cycle: %s\n", rank, o.message.c_str());
    good = false;
  }
  return rendered(ctx, step(ctx, mesh, kBig + 8, 1, false), kBig + 8, rank) && good;
}

bool async_failure(pnb_context ctx, const OwnedMesh& mesh, int rank) {
  bool good = publish(ctx, mesh, rank);
  const Outcome first = rank == kFaultyRank ? outcome(ctx, pnb_execute(ctx, 0, 0)) : step(ctx, mesh, 0, 0, false);
  good = succeeded(first, "step 0 (handed to the worker)", rank) && good;
  // Rank 0's worker has surely failed by its next call; the other ranks call at once.
  if (rank == 0) usleep(300 * 1000);
  const Outcome between = step(ctx, mesh, 1, 0.5, false);
  good = succeeded(between, "step 1 at time 0.5 (renders nothing, waits for no worker)", rank) && good;
  good = failed_naming_it(step(ctx, mesh, 2, 1, false), "step 2 (the workers' failure of step 0)", rank) && good;
  good = succeeded(step(ctx, mesh, 3, 1.5, false), "step 3", rank) && good;
  good = succeeded(step(ctx, mesh, 4, 2, false), "step 4", rank) && good;
  return rendered(ctx, outcome(ctx, pnb_finalize(ctx)), 4, rank) && good;
}

bool other_time(pnb_context ctx, const OwnedMesh& mesh, int rank) {
  bool good = publish(ctx, mesh, rank);
  good = failed_naming_it(step(ctx, mesh, 0, rank == kFaultyRank ? 100 : 0, false), "step 0 (another time on rank 1)", rank) && good;
  good = rendered(ctx, step(ctx, mesh, 1, 1, false), 1, rank) && good;
  return rendered(ctx, step(ctx, mesh, 2, 2, false), 2, rank) && good;
}

// Steps on until rank 1's store fails to write; every rank's first failing call must be the same.
bool failed_write(pnb_context ctx, const OwnedMesh& mesh, int rank, const std::string& out) {
  bool good = publish(ctx, mesh, rank);
  if (rank == kFaultyRank) {
    signal(SIGXFSZ, SIG_IGN);  // a write past the limit then fails with EFBIG, as one on a full disk with ENOSPC
    const rlimit limit{4096, 4096};
    setrlimit(RLIMIT_FSIZE, &limit);
  }
  constexpr int kSteps = 24;
  int first_failure = -1;
  Outcome failure;
  for (int cycle = 0; cycle < kSteps; ++cycle) {
    const Outcome o = step(ctx, mesh, cycle, cycle, false);
    if (o.status != PNB_OK && first_failure < 0) first_failure = cycle, failure = o;
  }
  const Outcome finalized = outcome(ctx, pnb_finalize(ctx));
  if (first_failure < 0 && finalized.status != PNB_OK) first_failure = kSteps, failure = finalized;
  int least = 0, most = 0;
  MPI_Allreduce(&first_failure, &least, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
  MPI_Allreduce(&first_failure, &most, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
  std::printf("rank %d: first failure at call %d of %d: %s\n", rank, first_failure, kSteps, failure.message.c_str());
  if (first_failure < 0 || least != most) {
    std::fprintf(stderr, "rank %d: the ranks' first failures differ or none failed (%d .. %d)\n", rank, least, most);
    good = false;
  }
  good = failed_naming_it(failure, "the failed write", rank) && good;
  if (rank == 0) {
    // The database stays readable and lists the steps rendered before the failure.
    std::ifstream csv(out + "/db/data.csv");
    std::string line;
    int rows = -1;
    for (; std::getline(csv, line); ++rows) {
    }
    std::printf("rank 0: data.csv lists %d steps\n", rows);
    if (rows < std::min(first_failure, kSteps)) good = false;
  }
  return good;
}

bool run(pnb_context ctx, const std::string& kind, const OwnedMesh& mesh, int rank, const std::string& out) {
  if (kind == "nan") return nan_field(ctx, mesh, rank);
  if (kind == "index") return bad_index(ctx, mesh, rank);
  if (kind == "empty") return refused_descriptor(ctx, mesh, rank);
  if (kind == "time") return other_time(ctx, mesh, rank);
  if (kind == "cycle") return other_cycle(ctx, mesh, rank);
  if (kind == "async") return async_failure(ctx, mesh, rank);
  if (kind == "write") return failed_write(ctx, mesh, rank, out);
  std::fprintf(stderr, "unknown failure kind %s\n", kind.c_str());
  return false;
}

}  // namespace

int main(int argc, char** argv) {
  const bool async = argc == 3 && std::string(argv[2]) == "async";
  int provided = MPI_THREAD_SINGLE;
  MPI_Init_thread(&argc, &argv, async ? MPI_THREAD_MULTIPLE : MPI_THREAD_SINGLE, &provided);
  int rank = 0, ranks = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &ranks);
  if (argc != 3 || ranks <= kFaultyRank || (async && provided != MPI_THREAD_MULTIPLE)) {
    if (rank == 0) std::fprintf(stderr, "usage: mpirun -np 3 %s OUT_DIR nan|index|empty|time|cycle|write|async\n", argv[0]);
    MPI_Finalize();
    return 2;
  }
  alarm(60);
  const std::string out = argv[1], kind = argv[2];
  if (rank == 0) fs::remove_all(out);
  MPI_Barrier(MPI_COMM_WORLD);
  const auto part = penumbra::mpi_test::partition(penumbra::fixtures::tet_block_with_hole(6), "slabs", rank, ranks, false);
  pnb_context ctx = nullptr;
  int good = succeeded(outcome(nullptr, pnb_create_mpi(config(out, async).c_str(), MPI_COMM_WORLD, &ctx)), "pnb_create_mpi", rank) ? 1 : 0;
  if (ctx) {
    good = run(ctx, kind, part.mesh, rank, out) ? good : 0;
    pnb_destroy(ctx);
  }
  int all = 0;
  MPI_Allreduce(&good, &all, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
  MPI_Finalize();
  return all ? 0 : 1;
}

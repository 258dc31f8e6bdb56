// SPDX-License-Identifier: BSD-3-Clause
// tests/mpi/mpi_render_test.cpp -- one run over the ranks of MPI_COMM_WORLD, each publishing its
// partition of a non-convex mesh, against the same mesh rendered whole in one process.
//
// Usage (under mpirun): penumbra_mpi_render_test OUT_DIR PARTITION LIGHTING BACKEND [fail=RANK] [ghosts]
//                                                [async] [threads=multiple]
//   PARTITION  slabs (cells by centroid x) | metis (METIS_PartMeshDual: non-convex parts, as a
//              solver's partitioner cuts them) | round-robin (cell c on rank c mod ranks: every ray
//              enters every rank many times, the worst case)
//   LIGHTING   none | phong | light-volume | scattering (the light volume scattering too) |
//              occlusion (cone-traced, in space "points") | occlusion-image-refused (image-space
//              occlusion with shadows: refused by every rank's pnb_create_mpi) | tight-runs (the runs' memory bound set below what
//              the views need: every rank's step fails naming a rank);  BACKEND cpu | gpu
//   fail=RANK  that rank publishes a field of the wrong size at the first step: every rank's
//              pnb_execute must fail naming it, and the next step must render.
//   empty=RANK that rank publishes no cell and no point (a rank that holds none of the rendered
//              region); the others share the whole mesh as RANKS - 1 parts
//   ghosts     each rank also publishes, as ghost cells (vtkGhostType), the cells of other ranks
//              that share a point with its own, and a cell field C is rendered too: averaged at the
//              points over the ghosts as well, it matches the one-process average at partition
//              boundaries, and no ghost is drawn twice.
//   async      the config asks for "async": with threads=multiple (MPI_Init_thread at
//              MPI_THREAD_MULTIPLE) the steps render on a worker on every rank; without it the
//              steps run inside pnb_execute and rank 0 says so once on stderr, checked here.
//   LIGHTING async-skip: "async" with "backpressure": "skip" over many quick steps: every rank
//              skips the same steps (no rank waits alone in a collective) and rank 0's database
//              lists the others.
//   LIGHTING budget: "budget" far below any step: every rank plans the same degraded steps.
// Exits 0 on every rank when rank 0's pictures are the whole mesh's within RMS 0.1 % of 255 and
// 2 levels (the runs of different ranks are composited in float32; the one-process render
// stops a ray at opacity 0.999, the ranks' runs do not), else 1; the light volume on round-robin
// cells has a wider bound (tolerance()).
#include <mpi.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "fixtures/meshes.h"
#include "mpi_partition.h"
#include "penumbra/penumbra_mpi.h"
#include "penumbra/render/image.h"

namespace {

namespace fs = std::filesystem;
using penumbra::fixtures::OwnedMesh;
using penumbra::mpi_test::field_at;
using penumbra::mpi_test::Part;
using penumbra::mpi_test::partition;

// A cell field over the whole mesh: its cells' index, scrambled (neighbouring cells differ).
double cell_value(std::size_t whole_cell) { return static_cast<double>((whole_cell * 7919) % 101) / 100.0; }

std::string config(const std::string& dir, const std::string& lighting, const std::string& backend, bool cell_field) {
  std::string c = R"({"output": {"directory": ")" + dir + R"("}, "backend": ")" + backend + R"(",
      "image": {"width": 96, "height": 72}, "cameras": {"phi": [30, 210], "theta": [20]},
      "fields": [{"name": "T", "transfer_function": {"colors": [[0, 0.1, 0.2, 0.9], [0.5, 0.9, 0.9, 0.2], [1, 1, 0.2, 0.1]],
                                                     "opacities": [[0, 1], [1, 10]]}})" +
                  std::string(cell_field ? R"(, {"name": "C", "range": [0, 1]}])" : "]");
  if (lighting == "phong") c += R"(, "lighting": {"model": "phong"})";
  if (lighting == "occlusion" || lighting == "occlusion-image")
    c += R"(, "lighting": {"model": "occlusion", "occlusion": {"grid": 48, "space": ")" +
         std::string(lighting == "occlusion" ? "points" : "image") + R"("},
                           "lights": [{"type": "directional", "direction": [-0.6, 0.3, -1]}]})";
  if (lighting == "light-volume" || lighting == "scattering")
    c += R"(, "lighting": {"model": "light-volume", "level0_resolution": 48, "absorption": 1,)" +
         std::string(lighting == "scattering" ? R"( "scattering": [0.5, 1, 2],)" : "") + R"(
                           "lights": [{"type": "directional", "direction": [-0.6, 0.3, -1]}]})";
  return c + "}";
}

bool ok(pnb_context ctx, pnb_status s, const char* what, int rank) {
  if (s == PNB_OK) return true;
  std::fprintf(stderr, "rank %d: %s: %s\n", rank, what, pnb_last_error(ctx));
  return false;
}

// Publishes `part` and runs steps 0 and 1; with `fail`, step 0's field has one value too few.
// Returns whether every call that should succeed did, and every call that should fail did.
bool run(pnb_context ctx, const Part& part, int rank, bool fail, int fail_rank) {
  const OwnedMesh& mesh = part.mesh;
  pnb_mesh_desc m = penumbra::mpi_test::mesh_desc(mesh);
  m.cell_ghosts = part.ghosts.empty() ? nullptr : part.ghosts.data();
  if (!ok(ctx, pnb_publish_mesh(ctx, &m, PNB_BORROW), "pnb_publish_mesh", rank)) return false;
  std::vector<double> cells(part.whole_cell.size());
  for (std::size_t c = 0; c < cells.size(); ++c) cells[c] = cell_value(part.whole_cell[c]);
  pnb_field_desc cf = PNB_FIELD_DESC_INIT;
  cf.name = "C";
  cf.association = PNB_CELL_FIELD;
  cf.values = cells.data();
  cf.count = static_cast<int64_t>(cells.size());
  if (!ok(ctx, pnb_publish_field(ctx, &cf, PNB_COPY), "pnb_publish_field(C)", rank)) return false;
  bool good = true;
  for (int step = 0; step < 2; ++step) {
    const auto values = penumbra::fixtures::sample(mesh, [step](double x, double y, double z) { return field_at(x, y, z, step); });
    pnb_field_desc f = PNB_FIELD_DESC_INIT;
    f.name = "T";
    f.values = values.data();
    f.count = static_cast<int64_t>(values.size()) - (fail && step == 0 && rank == fail_rank ? 1 : 0);
    const pnb_status published = pnb_publish_field(ctx, &f, PNB_BORROW);
    const pnb_status executed = pnb_execute(ctx, step, step);
    if (fail && step == 0) {
      // Every rank's status names the failing rank.
      const std::string text = pnb_last_error(ctx);
      const bool named = executed != PNB_OK && text.find("rank " + std::to_string(fail_rank)) != std::string::npos;
      if (!named) std::fprintf(stderr, "rank %d: expected step 0 to fail naming rank %d, got %d: %s\n", rank, fail_rank,
                               static_cast<int>(executed), text.c_str());
      good = good && named && (rank == fail_rank ? published != PNB_OK : published == PNB_OK);
      continue;
    }
    good = ok(ctx, published, "pnb_publish_field", rank) && ok(ctx, executed, "pnb_execute", rank) && good;
  }
  return good;
}

// How far the ranks' pictures may be from the one-process ones.
struct Tolerance {
  double rms_pct = 0.1;
  int levels = 2;
};

// Unlit and Phong: the composited runs (see the top). The light volume over ranks continues each
// level-1 walk that leaves its rank's cells in the merged level 0 (docs/distributed.md): on slabs
// and METIS parts few walks do, and the pictures hold the same bounds; round-robin cells send
// every walk into level 0 after one tet, so the light there is about level 0's.
Tolerance tolerance(const std::string& lighting, const std::string& kind) {
  if ((lighting == "light-volume" || lighting == "scattering") && kind == "round-robin") return {0.35, 6};
  return {};
}

// Rank 0: every image of `dir` against the same file under `reference`.
bool same_pictures(const std::string& dir, const std::string& reference, bool fail, const Tolerance& tol) {
  bool good = true;
  int compared = 0;
  for (const auto& e : fs::recursive_directory_iterator(reference)) {
    if (e.path().extension() != ".png") continue;
    const std::string rel = fs::relative(e.path(), reference).string();
    if (fail && rel.find("c000000") != std::string::npos) continue;  // the failed step
    int w1 = 0, h1 = 0, w2 = 0, h2 = 0;
    const auto a = penumbra::render::read_png_rgb(e.path().string(), w1, h1);
    const auto b = penumbra::render::read_png_rgb(dir + "/" + rel, w2, h2);
    int worst = 0;
    for (std::size_t i = 0; i < a.size() && i < b.size(); ++i) worst = std::max(worst, std::abs(int(a[i]) - int(b[i])));
    const double rms = penumbra::render::rms_difference_pct(a, b);
    std::printf("%s: RMS %.4f %%, %d levels at most\n", rel.c_str(), rms, worst);
    good = good && a.size() == b.size() && rms <= tol.rms_pct && worst <= tol.levels;
    ++compared;
  }
  return good && compared > 0;
}

// What a run over several ranks refuses at creation, with a message naming it: image-space
// occlusion with shadows (its gaps start at every ray sample). pnb_create_mpi fails on every rank.
int refused(const std::string& dir, const std::string& backend, int rank) {
  const std::string c = config(dir, "occlusion-image", backend, false);
  const std::string named = "\"image\" with shadows";
  pnb_context ctx = nullptr;
  const pnb_status s = pnb_create_mpi(c.c_str(), MPI_COMM_WORLD, &ctx);
  const std::string text = pnb_last_error(nullptr);
  int good = s != PNB_OK && ctx == nullptr && text.find(named) != std::string::npos ? 1 : 0;
  if (!good) std::fprintf(stderr, "rank %d: expected pnb_create_mpi to refuse %s, got %d: %s\n", rank, named.c_str(), int(s), text.c_str());
  if (ctx) pnb_destroy(ctx);
  int all = 0;
  MPI_Allreduce(&good, &all, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
  MPI_Finalize();
  return all ? 0 : 1;
}

// Runs over their memory bound ("compositing": {"runs_memory_mb"}): every rank's step fails with
// an error that names a rank and the runs, and none is left waiting.
int runs_over_budget(const std::string& dir, const std::string& backend, const Part& part, int rank) {
  std::string c = config(dir, "none", backend, false);
  c.insert(c.rfind('}'), R"(, "compositing": {"runs_memory_mb": 0.2})");
  pnb_context ctx = nullptr;
  int good = ok(nullptr, pnb_create_mpi(c.c_str(), MPI_COMM_WORLD, &ctx), "pnb_create_mpi", rank) ? 1 : 0;
  if (ctx) {
    const OwnedMesh& mesh = part.mesh;
    const pnb_mesh_desc m = penumbra::mpi_test::mesh_desc(mesh);
    const auto values = penumbra::fixtures::sample(mesh, [](double x, double y, double z) { return field_at(x, y, z, 0); });
    pnb_field_desc f = PNB_FIELD_DESC_INIT;
    f.name = "T";
    f.values = values.data();
    f.count = static_cast<int64_t>(values.size());
    const bool published = ok(ctx, pnb_publish_mesh(ctx, &m, PNB_BORROW), "pnb_publish_mesh", rank) &&
                           ok(ctx, pnb_publish_field(ctx, &f, PNB_BORROW), "pnb_publish_field", rank);
    const pnb_status executed = pnb_execute(ctx, 0, 0);
    const std::string text = pnb_last_error(ctx);
    const bool refused = executed == PNB_OUT_OF_MEMORY && text.find("rank ") != std::string::npos &&
                         text.find("ray runs") != std::string::npos;
    if (!refused) std::fprintf(stderr, "rank %d: expected the step to fail on the runs' bound, got %d: %s\n", rank, int(executed), text.c_str());
    good = published && refused ? good : 0;
    pnb_destroy(ctx);
  }
  int all = 0;
  MPI_Allreduce(&good, &all, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
  MPI_Finalize();
  return all ? 0 : 1;
}

// "trigger": {"when": "max(S) > 2.5"} on slabs along x with S = k x at step k: each rank's own
// maximum crosses 2.5 at another step, the reduced one at k = 3, so every rank renders steps 4
// and 5 (the decision reads the step before), pnb_step_needs says so on every rank, and no rank
// is told the others disagree.
int when_trigger(const std::string& dir, const Part& part, int rank) {
  std::string c = config(dir, "none", "cpu", false);
  c.insert(c.rfind('}'), R"(, "trigger": {"when": "max(S) > 2.5"})");
  pnb_context ctx = nullptr;
  int good = ok(nullptr, pnb_create_mpi(c.c_str(), MPI_COMM_WORLD, &ctx), "pnb_create_mpi", rank) ? 1 : 0;
  if (ctx) {
    const OwnedMesh& mesh = part.mesh;
    const pnb_mesh_desc m = penumbra::mpi_test::mesh_desc(mesh);
    good = ok(ctx, pnb_publish_mesh(ctx, &m, PNB_BORROW), "pnb_publish_mesh", rank) ? good : 0;
    double lo = 1e300, hi = -1e300;
    for (std::size_t i = 0; i < mesh.point_count(); ++i) lo = std::min(lo, mesh.xyz[3 * i]), hi = std::max(hi, mesh.xyz[3 * i]);
    std::string rendered;
    for (int k = 0; k < 6; ++k) {
      pnb_needs needs = PNB_NEEDS_INIT;
      good = ok(ctx, pnb_step_needs(ctx, k, k, &needs), "pnb_step_needs", rank) ? good : 0;
      // x spans the whole block's [lo, hi] over the ranks; S = k (x - lo) / (hi - lo) there.
      const auto t = penumbra::fixtures::sample(mesh, [](double x, double y, double z) { return field_at(x, y, z, 0); });
      const auto s = penumbra::fixtures::sample(mesh, [k](double x, double, double) { return k * x; });
      pnb_field_desc f = PNB_FIELD_DESC_INIT, g = PNB_FIELD_DESC_INIT;
      f.name = "T", f.values = t.data(), f.count = static_cast<int64_t>(t.size());
      g.name = "S", g.values = s.data(), g.count = static_cast<int64_t>(s.size());
      pnb_publish_field(ctx, &f, PNB_BORROW);
      pnb_publish_field(ctx, &g, PNB_BORROW);
      good = ok(ctx, pnb_execute(ctx, k, k), "pnb_execute", rank) ? good : 0;
      pnb_step_stats stats = PNB_STEP_STATS_INIT;
      pnb_last_step(ctx, &stats);
      const bool did = stats.cycle == k && stats.total_ms > 0;  // images: rank 0 writes them
      if (did != (needs.renders == 1)) good = 0;
      if (did) rendered += std::to_string(k);
    }
    if (rendered != "45") {
      std::fprintf(stderr, "rank %d (x in [%g, %g]): rendered steps '%s', expected '45'\n", rank, lo, hi, rendered.c_str());
      good = 0;
    }
    pnb_destroy(ctx);
  }
  int all = 0;
  MPI_Allreduce(&good, &all, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
  MPI_Finalize();
  return all ? 0 : 1;
}

// What `call` writes on stderr, taken from its file descriptor; returns what `call` returns.
template <class Call>
pnb_status stderr_of(Call&& call, std::string& text) {
  std::fflush(stderr);
  std::FILE* capture = std::tmpfile();
  const int saved = dup(2);
  if (capture) dup2(fileno(capture), 2);
  const pnb_status s = call();
  std::fflush(stderr);
  if (capture) {
    dup2(saved, 2);
    std::rewind(capture);
    char buffer[512];
    std::size_t n = 0;
    while ((n = std::fread(buffer, 1, sizeof buffer, capture)) > 0) text.append(buffer, n);
    std::fclose(capture);
  }
  close(saved);
  return s;
}

// "async" with "backpressure": "skip": twelve quick steps, so that workers are busy when steps
// come. Every rank must skip the same steps (else a collective would wait on the ranks that
// skipped: the test's TIMEOUT), and rank 0's database lists every step not skipped.
int async_skip(const std::string& dir, const Part& part, int rank) {
  std::string c = config(dir, "light-volume", "cpu", false);
  c.insert(c.rfind('}'), R"(, "async": {"backpressure": "skip"})");
  pnb_context ctx = nullptr;
  int good = ok(nullptr, pnb_create_mpi(c.c_str(), MPI_COMM_WORLD, &ctx), "pnb_create_mpi", rank) ? 1 : 0;
  long long skipped = -1;
  if (ctx) {
    const pnb_mesh_desc m = penumbra::mpi_test::mesh_desc(part.mesh);
    good = ok(ctx, pnb_publish_mesh(ctx, &m, PNB_BORROW), "pnb_publish_mesh", rank) ? good : 0;
    std::vector<double> values;
    for (int k = 0; k < 12; ++k) {
      values = penumbra::fixtures::sample(part.mesh, [k](double x, double y, double z) { return field_at(x, y, z, k % 2); });
      pnb_field_desc f = PNB_FIELD_DESC_INIT;
      f.name = "T", f.values = values.data(), f.count = static_cast<int64_t>(values.size());
      pnb_publish_field(ctx, &f, PNB_BORROW);
      good = ok(ctx, pnb_execute(ctx, k, k), "pnb_execute", rank) ? good : 0;
      usleep(15000);  // a solver step: some steps find the workers done, some (on some ranks) not
    }
    good = ok(ctx, pnb_finalize(ctx), "pnb_finalize", rank) ? good : 0;
    pnb_step_stats stats = PNB_STEP_STATS_INIT;
    pnb_last_step(ctx, &stats);
    skipped = static_cast<long long>(stats.skipped_steps);
    pnb_destroy(ctx);
  }
  long long least = 0, most = 0;
  MPI_Allreduce(&skipped, &least, 1, MPI_LONG_LONG, MPI_MIN, MPI_COMM_WORLD);
  MPI_Allreduce(&skipped, &most, 1, MPI_LONG_LONG, MPI_MAX, MPI_COMM_WORLD);
  if (least != most) {
    std::fprintf(stderr, "rank %d: skipped %lld steps; the ranks skipped %lld to %lld\n", rank, skipped, least, most);
    good = 0;
  }
  if (rank == 0) {
    std::ifstream csv(dir + "/data.csv");
    long long lines = 0;
    for (std::string line; std::getline(csv, line);) ++lines;
    const long long expected = 1 + 2 * (12 - skipped);  // the header, then two cameras per step
    std::printf("async skip: %lld of 12 steps skipped on every rank; data.csv has %lld lines\n", skipped, lines);
    if (lines != expected) {
      std::fprintf(stderr, "rank 0: data.csv has %lld lines, expected %lld\n", lines, expected);
      good = 0;
    }
  }
  int all = 0;
  MPI_Allreduce(&good, &all, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
  MPI_Finalize();
  return all ? 0 : 1;
}

// "budget" far below any step: every rank plans the same degraded steps from the largest costs
// (level 0 coarsened, the images smaller, one camera a step), and rank 0 lists what it gave up.
int budget_steps(const std::string& dir, const Part& part, int rank) {
  std::string c = config(dir, "light-volume", "cpu", false);
  c.insert(c.rfind('}'), R"(, "budget": {"ms": 0.001})");
  pnb_context ctx = nullptr;
  int good = ok(nullptr, pnb_create_mpi(c.c_str(), MPI_COMM_WORLD, &ctx), "pnb_create_mpi", rank) ? 1 : 0;
  double plan[4] = {-1, -1, -1, -1};  // degraded bits, cameras, image scale, level 0
  if (ctx) {
    const pnb_mesh_desc m = penumbra::mpi_test::mesh_desc(part.mesh);
    good = ok(ctx, pnb_publish_mesh(ctx, &m, PNB_BORROW), "pnb_publish_mesh", rank) ? good : 0;
    for (int k = 0; k < 3; ++k) {
      const auto values = penumbra::fixtures::sample(part.mesh, [k](double x, double y, double z) { return field_at(x, y, z, k); });
      pnb_field_desc f = PNB_FIELD_DESC_INIT;
      f.name = "T", f.values = values.data(), f.count = static_cast<int64_t>(values.size());
      pnb_publish_field(ctx, &f, PNB_BORROW);
      good = ok(ctx, pnb_execute(ctx, k, k), "pnb_execute", rank) ? good : 0;
    }
    pnb_step_stats stats = PNB_STEP_STATS_INIT;
    pnb_last_step(ctx, &stats);
    plan[0] = stats.degraded, plan[1] = stats.cameras_rendered, plan[2] = stats.image_scale, plan[3] = stats.level0_resolution;
    pnb_destroy(ctx);
  }
  double least[4], most[4];
  MPI_Allreduce(plan, least, 4, MPI_DOUBLE, MPI_MIN, MPI_COMM_WORLD);
  MPI_Allreduce(plan, most, 4, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  for (int i = 0; i < 4; ++i)
    if (least[i] != most[i]) {
      std::fprintf(stderr, "rank %d: the ranks' plans differ in item %d (%g .. %g)\n", rank, i, least[i], most[i]);
      good = 0;
    }
  const bool degraded = plan[1] == 1 && plan[2] == 0.25 && plan[3] == 16 && (static_cast<int>(plan[0]) & PNB_DEGRADED_CAMERAS);
  if (!degraded) {
    std::fprintf(stderr, "rank %d: degraded %g, cameras %g, image scale %g, level 0 %g\n", rank, plan[0], plan[1], plan[2], plan[3]);
    good = 0;
  }
  if (rank == 0) {
    std::ifstream csv(dir + "/data.csv");
    std::string header, line;
    std::getline(csv, header);
    int rows = 0, degraded_rows = 0;
    for (; std::getline(csv, line); ++rows) degraded_rows += line.find("level0:16+image:0.25+cameras:1/2") != std::string::npos;
    std::printf("budget: %s; %d rows, %d of them degraded\n", header.c_str(), rows, degraded_rows);
    if (header.find(",degraded,") == std::string::npos || rows != 4 || degraded_rows != 2) good = 0;
  }
  int all = 0;
  MPI_Allreduce(&good, &all, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
  MPI_Finalize();
  return all ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  bool threads_multiple = false, async = false;
  for (int a = 5; a < argc; ++a) {
    threads_multiple = threads_multiple || std::string(argv[a]) == "threads=multiple";
    async = async || std::string(argv[a]) == "async";
  }
  int provided = MPI_THREAD_SINGLE;
  MPI_Init_thread(&argc, &argv, threads_multiple ? MPI_THREAD_MULTIPLE : MPI_THREAD_SINGLE, &provided);
  if (threads_multiple && provided != MPI_THREAD_MULTIPLE) {
    std::fprintf(stderr, "this MPI does not provide MPI_THREAD_MULTIPLE (gave %d)\n", provided);
    MPI_Finalize();
    return 1;
  }
  int rank = 0, ranks = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &ranks);
  if (argc < 5) {
    if (rank == 0) std::fprintf(stderr, "usage: %s OUT_DIR PARTITION LIGHTING BACKEND [FAIL_RANK]\n", argv[0]);
    MPI_Finalize();
    return 2;
  }
  const std::string out = argv[1], kind = argv[2], lighting = argv[3], backend = argv[4];
  int fail_rank = -1, empty_rank = -1;
  bool ghosts = false;
  for (int a = 5; a < argc; ++a) {
    const std::string option = argv[a];
    if (option.rfind("fail=", 0) == 0) fail_rank = std::atoi(option.c_str() + 5);
    if (option.rfind("empty=", 0) == 0) empty_rank = std::atoi(option.c_str() + 6);
    ghosts = ghosts || option == "ghosts";
  }
  const bool fail = fail_rank >= 0;
  const std::string dir = out + "/ranks", reference = out + "/serial";
  if (rank == 0) fs::remove_all(out);
  MPI_Barrier(MPI_COMM_WORLD);
  if (lighting == "occlusion-image-refused") return refused(dir, backend, rank);
  if (lighting == "budget") return budget_steps(dir, partition(penumbra::fixtures::tet_block_with_hole(8), kind, rank, ranks, false), rank);
  if (lighting == "async-skip") return async_skip(dir, partition(penumbra::fixtures::tet_block_with_hole(8), kind, rank, ranks, false), rank);
  if (lighting == "when-trigger") return when_trigger(dir, partition(penumbra::fixtures::tet_block_with_hole(8), kind, rank, ranks, false), rank);
  if (lighting == "tight-runs") return runs_over_budget(dir, backend, partition(penumbra::fixtures::tet_block_with_hole(8), kind, rank, ranks, false), rank);

  const OwnedMesh whole = penumbra::fixtures::tet_block_with_hole(8);
  int good = 1;
  pnb_context ctx = nullptr;
  std::string c = config(dir, lighting, backend, ghosts);
  if (async) c.insert(c.rfind('}'), R"(, "async": true)");
  std::string said;
  const pnb_status created = stderr_of([&] { return pnb_create_mpi(c.c_str(), MPI_COMM_WORLD, &ctx); }, said);
  std::fputs(said.c_str(), stderr);
  if (!ok(nullptr, created, "pnb_create_mpi", rank)) good = 0;
  if (async && !threads_multiple && rank == 0 && said.find("needs MPI_THREAD_MULTIPLE") == std::string::npos) {
    std::fprintf(stderr, "rank 0: \"async\" below MPI_THREAD_MULTIPLE did not say that its steps run inside pnb_execute\n");
    good = 0;
  }
  if (ctx) {
    good = run(ctx, penumbra::mpi_test::part_of(whole, kind, rank, ranks, ghosts, empty_rank), rank, fail, fail_rank) ? good : 0;
    pnb_destroy(ctx);
  }
  if (rank == 0) {
    pnb_context serial = nullptr;
    std::string serial_config = config(reference, lighting, backend, ghosts);
    if (async) serial_config.insert(serial_config.rfind('}'), R"(, "async": true)");
    if (!ok(nullptr, pnb_create(serial_config.c_str(), &serial), "pnb_create", rank)) good = 0;
    if (serial) {
      good = run(serial, partition(whole, kind, 0, 1, false), rank, false, -1) ? good : 0;
      pnb_destroy(serial);
      good = same_pictures(dir, reference, fail, tolerance(lighting, kind)) ? good : 0;
    }
  }
  int all = 0;
  MPI_Allreduce(&good, &all, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
  MPI_Finalize();
  return all ? 0 : 1;
}

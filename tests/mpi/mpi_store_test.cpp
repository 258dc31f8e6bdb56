// SPDX-License-Identifier: BSD-3-Clause
// tests/mpi/mpi_store_test.cpp -- a run over MPI ranks that keeps its history (config "store"),
// is killed on one rank, restarts from a checkpoint on another rank count, and is replayed; driven
// by store_kill_restart.sh.
//
// Usage:
//   penumbra_mpi_store_test write OUT PARTITION FIRST LAST [kill=RANK@STEP] [resume] [empty=RANK] [ghosts]
//       (under mpirun) steps FIRST..LAST-1 of the test mesh cut by PARTITION into OUT/db and
//       OUT/store; with kill, rank RANK aborts once step STEP is rendered (mpirun then kills the
//       others); with resume, the database is resumed (a restart from a checkpoint); with empty,
//       rank RANK publishes no cell and the others split the mesh among themselves; with ghosts,
//       each rank also publishes its neighbours' cells that share its points, marked ghost
//   penumbra_mpi_store_test reference OUT FIRST LAST   the whole mesh, exact fields, one process,
//       into OUT/reference
//   penumbra_mpi_store_test config DIR                 prints the config that renders into DIR
//   penumbra_mpi_store_test compare A B RMS LEVELS     every picture of A against B's of the same
//       name: RMS (% of 255) and largest difference (levels) within the bounds, B's index listing
//       every cycle of A's
#include <mpi.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
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

std::string config(const std::string& dir, const std::string& store, bool resume) {
  std::string c = R"({"output": {"directory": ")" + dir + R"(")" + (resume ? R"(, "if_exists": "resume")" : "") + R"(},
      "image": {"width": 96, "height": 72}, "cameras": {"phi": [30, 210], "theta": [20]},
      "fields": [{"name": "T", "range": [-2, 3],
                  "transfer_function": {"colors": [[0, 0.1, 0.2, 0.9], [0.5, 0.9, 0.9, 0.2], [1, 1, 0.2, 0.1]],
                                        "opacities": [[0, 1], [1, 10]]}}])";
  if (!store.empty()) c += R"(, "store": {"directory": ")" + store + R"(", "window": 8})";
  return c + "}";
}

bool ok(pnb_context ctx, pnb_status s, const char* what) {
  if (s == PNB_OK) return true;
  std::fprintf(stderr, "%s: %s\n", what, pnb_last_error(ctx));
  return false;
}

// Publishes `mesh` (its cells marked by `ghosts` when given) and renders steps [first, last);
// `kill` aborts after step kill_step.
bool run_steps(pnb_context ctx, const OwnedMesh& mesh, const std::vector<std::uint8_t>& ghosts, int first, int last,
               int kill_step) {
  pnb_mesh_desc m = penumbra::mpi_test::mesh_desc(mesh);
  m.cell_ghosts = ghosts.empty() ? nullptr : ghosts.data();
  if (!ok(ctx, pnb_publish_mesh(ctx, &m, PNB_BORROW), "pnb_publish_mesh")) return false;
  for (int step = first; step < last; ++step) {
    const auto values = penumbra::fixtures::sample(mesh, [step](double x, double y, double z) { return field_at(x, y, z, step); });
    pnb_field_desc f = PNB_FIELD_DESC_INIT;
    f.name = "T";
    f.values = values.data();
    f.count = static_cast<int64_t>(values.size());
    if (!ok(ctx, pnb_publish_field(ctx, &f, PNB_BORROW), "pnb_publish_field") ||
        !ok(ctx, pnb_execute(ctx, step, step), "pnb_execute"))
      return false;
    if (step == kill_step) std::abort();  // killed: no finalize, no destructor
  }
  return ok(ctx, pnb_finalize(ctx), "pnb_finalize");
}

int write(const std::vector<std::string>& a) {
  int rank = 0, ranks = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &ranks);
  const std::string out = a.at(0), kind = a.at(1);
  const int first = std::stoi(a.at(2)), last = std::stoi(a.at(3));
  int kill_step = -1, empty_rank = -1;
  bool resume = false, ghosts = false;
  for (std::size_t i = 4; i < a.size(); ++i) {
    if (a[i].rfind("kill=", 0) == 0 && std::stoi(a[i].substr(5)) == rank) kill_step = std::stoi(a[i].substr(a[i].find('@') + 1));
    resume = resume || a[i] == "resume";
    ghosts = ghosts || a[i] == "ghosts";
    if (a[i].rfind("empty=", 0) == 0) empty_rank = std::stoi(a[i].substr(6));
  }
  const auto whole = penumbra::fixtures::tet_block_with_hole(8);
  const penumbra::mpi_test::Part part = penumbra::mpi_test::part_of(whole, kind, rank, ranks, ghosts, empty_rank);
  pnb_context ctx = nullptr;
  int good = ok(nullptr, pnb_create_mpi(config(out + "/db", out + "/store", resume).c_str(), MPI_COMM_WORLD, &ctx),
                "pnb_create_mpi") ? 1 : 0;
  if (ctx) {
    good = run_steps(ctx, part.mesh, part.ghosts, first, last, kill_step) ? good : 0;
    pnb_destroy(ctx);
  }
  int all = 0;
  MPI_Allreduce(&good, &all, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
  return all ? 0 : 1;
}

int reference(const std::vector<std::string>& a) {
  pnb_context ctx = nullptr;
  if (!ok(nullptr, pnb_create(config(a.at(0) + "/reference", "", false).c_str(), &ctx), "pnb_create")) return 1;
  const bool good = run_steps(ctx, penumbra::fixtures::tet_block_with_hole(8), {}, std::stoi(a.at(1)), std::stoi(a.at(2)), -1);
  pnb_destroy(ctx);
  return good ? 0 : 1;
}

// The cycles an image database's index lists (its data.csv's first column).
std::set<std::string> cycles_listed(const std::string& db) {
  std::set<std::string> cycles;
  std::ifstream in(db + "/data.csv");
  std::string line;
  std::getline(in, line);  // header
  while (std::getline(in, line))
    if (!line.empty()) cycles.insert(line.substr(0, line.find(',')));
  return cycles;
}

int compare(const std::vector<std::string>& a) {
  const std::string reference = a.at(0), dir = a.at(1);
  const double rms_bound = std::stod(a.at(2));
  const int level_bound = std::stoi(a.at(3));
  bool good = cycles_listed(reference) == cycles_listed(dir) && !cycles_listed(dir).empty();
  if (!good) std::fprintf(stderr, "%s and %s list different cycles\n", reference.c_str(), dir.c_str());
  int compared = 0;
  for (const auto& e : fs::recursive_directory_iterator(reference)) {
    if (e.path().extension() != ".png") continue;
    const std::string rel = fs::relative(e.path(), reference).string();
    int w1 = 0, h1 = 0, w2 = 0, h2 = 0;
    std::vector<std::uint8_t> x, y;
    try {
      x = penumbra::render::read_png_rgb(e.path().string(), w1, h1);
      y = penumbra::render::read_png_rgb(dir + "/" + rel, w2, h2);
    } catch (const std::exception& ex) {
      std::fprintf(stderr, "%s: %s\n", rel.c_str(), ex.what());
      good = false;
      continue;
    }
    int worst = 0;
    for (std::size_t i = 0; i < x.size() && i < y.size(); ++i) worst = std::max(worst, std::abs(int(x[i]) - int(y[i])));
    const double rms = penumbra::render::rms_difference_pct(x, y);
    std::printf("%s: RMS %.4f %%, %d levels at most\n", rel.c_str(), rms, worst);
    good = good && x.size() == y.size() && rms <= rms_bound && worst <= level_bound;
    ++compared;
  }
  return good && compared > 0 ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  const std::vector<std::string> args(argv + 1, argv + argc);
  if (args.empty()) return 2;
  const std::vector<std::string> rest(args.begin() + 1, args.end());
  if (args[0] == "config" && rest.size() == 1) {
    std::printf("%s\n", config(rest[0], "", false).c_str());
    return 0;
  }
  if (args[0] == "compare" && rest.size() == 4) return compare(rest);
  if (args[0] == "reference" && rest.size() == 3) return reference(rest);
  if (args[0] != "write" || rest.size() < 4) return 2;
  MPI_Init(&argc, &argv);
  const int status = write(rest);
  MPI_Finalize();
  return status;
}

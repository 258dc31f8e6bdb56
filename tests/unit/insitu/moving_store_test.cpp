// SPDX-License-Identifier: BSD-3-Clause
// tests/unit/insitu/moving_store_test.cpp -- the compressed history of a mesh whose points move:
// one segment, coordinates within a bound tied to the thinnest cell (or exact), epochs as cells
// thin, a replay that moves the mesh with them
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "cinema_database.h"
#include "config.h"
#include "context.h"
#include "fixtures/meshes.h"
#include "penumbra/core/error.h"
#include "penumbra/insitu/stored_run.h"
#include "penumbra/render/image.h"
#include "penumbra/render/tet_mesh.h"
#include "test_util.h"

namespace penumbra::insitu {
namespace {

using fixtures::BlockCells;
using testing::TempDir;

const fixtures::OwnedMesh& base_mesh() {
  static const auto mesh = fixtures::block(BlockCells::hexes, 6, 6, 4, {0, 0, 0}, {1, 1, 1});
  return mesh;
}

// The mesh at step k of a Lagrangian run in a steady vortex.
fixtures::OwnedMesh swirled(int k) {
  auto m = base_mesh();
  fixtures::swirl(m, {0.5, 0.5, 0}, 0.6, 0.05 * k);
  return m;
}

std::vector<double> temperature(const fixtures::OwnedMesh& mesh, double t) {
  return fixtures::sample(mesh, [t](double x, double y, double z) { return std::sin(4 * x + t) * std::cos(3 * y) + z; });
}

std::string config(const std::string& db, const std::string& store, const std::string& store_extra = "") {
  return testing::small_config(db, R"([{"name": "T"}])",
                               R"(, "store": {"directory": ")" + store + R"(", "window": 8, "error_bound": {"absolute": 1e-4})" +
                                   store_extra + "}");
}

// Runs `steps` steps of `mesh_at` (published under one topology_version) with the store.
void run(const std::string& db, const std::string& store, int steps,
         const std::function<fixtures::OwnedMesh(int)>& mesh_at, const std::string& store_extra = "") {
  Context ctx(parse_config(config(db, store, store_extra)));
  for (int k = 0; k < steps; ++k) {
    const auto mesh = mesh_at(k);
    ctx.publish_mesh(mesh.view());
    const auto v = temperature(mesh, 0.1 * k);
    ctx.publish_field(fixtures::point_field("T", v), false);
    ctx.execute(0.1 * k, k);
  }
  ctx.finalize();
}

double thinnest_altitude(const fixtures::OwnedMesh& mesh) {
  return render::smallest_altitude(render::prepare_tet_mesh(mesh.view()));
}

// The largest coordinate difference between a step's stored points and the mesh's.
double coordinate_error(StoredRun& stored, std::size_t step, const fixtures::OwnedMesh& mesh) {
  std::vector<double> xyz;
  stored.read_points(step, xyz);
  EXPECT_EQ(xyz.size(), mesh.xyz.size());
  double worst = 0;
  for (std::size_t i = 0; i < xyz.size() && i < mesh.xyz.size(); ++i) worst = std::max(worst, std::fabs(xyz[i] - mesh.xyz[i]));
  return worst;
}

TEST(MovingStore, OneSegmentHoldsTheCoordinatesWithinTheThinnestCellsBound) {
  TempDir tmp;
  run(tmp / "db", tmp / "store", 21, swirled);
  EXPECT_FALSE(std::filesystem::exists(tmp / "store/segment-001"));
  auto stored = StoredRun::open(tmp / "store/segment-000");
  ASSERT_TRUE(stored->points_move());
  ASSERT_EQ(stored->step_count(), 21u);
  // The default bound: 1/64 of the thinnest altitude, per coordinate over sqrt(3), from the first
  // moving step (the swirl barely thins the cells: one epoch).
  const double bound = thinnest_altitude(swirled(1)) / 64 / std::sqrt(3.0);
  EXPECT_EQ(coordinate_error(*stored, 0, swirled(0)), 0.0);  // before the motion: the mesh's own points
  for (int k = 1; k < 21; ++k) {
    const double e = coordinate_error(*stored, static_cast<std::size_t>(k), swirled(k));
    EXPECT_LE(e, bound * (1 + 1e-9)) << "step " << k;
  }
  EXPECT_GT(coordinate_error(*stored, 20, swirled(19)), 2 * bound);  // the steps are told apart
  // Every stored step's mesh is valid: no cell inverted by the coordinates' error.
  std::vector<double> xyz;
  for (std::size_t s = 0; s < stored->step_count(); ++s) {
    stored->read_points(s, xyz);
    MeshView view = stored->mesh();
    view.points = {reinterpret_cast<const std::byte*>(xyz.data()), view.point_count(), 3 * sizeof(double)};
    const auto prepared = render::prepare_tet_mesh(stored->mesh());
    EXPECT_NO_THROW(render::move_tet_mesh(prepared, view)) << "step " << s;
  }
}

TEST(MovingStore, LosslessCoordinatesReadBackBitForBit) {
  TempDir tmp;
  run(tmp / "db", tmp / "store", 11, swirled, R"(, "coordinates": "lossless")");
  auto stored = StoredRun::open(tmp / "store/segment-000");
  ASSERT_TRUE(stored->points_move());
  ASSERT_EQ(stored->step_count(), 11u);
  for (int k = 0; k < 11; ++k) EXPECT_EQ(coordinate_error(*stored, static_cast<std::size_t>(k), swirled(k)), 0.0);
  EXPECT_TRUE(std::filesystem::exists(tmp / "store/segment-000/coordinates/exact.pnbc"));
  EXPECT_FALSE(std::filesystem::exists(tmp / "store/segment-000/coordinates/epoch-000"));
}

// Cells flattened step by step (z squeezed by 10 % a step): once the thinnest altitude halves, the
// next epoch's bound follows it, so every step stays within 1/32 of its own thinnest altitude.
TEST(MovingStore, ThinningCellsStartEpochsWithTighterBounds) {
  TempDir tmp;
  const auto squeezed = [](int k) {
    auto m = swirled(k);
    for (std::size_t i = 0; i < m.point_count(); ++i) m.xyz[3 * i + 2] *= std::pow(0.9, k);
    return m;
  };
  run(tmp / "db", tmp / "store", 17, squeezed);
  EXPECT_TRUE(std::filesystem::exists(tmp / "store/segment-000/coordinates/epoch-001"));
  auto stored = StoredRun::open(tmp / "store/segment-000");
  ASSERT_EQ(stored->step_count(), 17u);
  for (int k = 1; k < 17; ++k) {
    const double e = coordinate_error(*stored, static_cast<std::size_t>(k), squeezed(k));
    EXPECT_LE(e, thinnest_altitude(squeezed(k)) / 32 / std::sqrt(3.0)) << "step " << k;
  }
}

std::vector<unsigned char> image(const std::string& db, std::size_t row) {
  const auto rows = CinemaDatabase::parse_csv(testing::read_text(db + "/data.csv"), "data.csv");
  int w = 0, h = 0;
  return render::read_png_rgb(db + "/" + rows[row].back(), w, h);
}

// The history re-rendered step by step, the mesh moved to each step's stored coordinates: the
// run's pictures within what the stored errors allow. With exact coordinates only the field's
// bound (1e-4 of a range of 2) is left: a level at most. With the default bound a point is off by at
// most 1/64 of the thinnest cell's altitude, so a ray's length in a cell changes by about 1.5 % of
// that cell's: a small RMS, and more than 2 levels only where a ray grazes the moved silhouette.
struct ReplayDifference {
  int worst = 0;
  double rms_pct = 0;
  double over_two_levels = 0;  ///< fraction of channel values off by more than 2 levels
};

ReplayDifference replay_difference(const std::string& store_extra) {
  TempDir tmp;
  const std::string db = tmp / "db", replayed = tmp / "replayed";
  run(db, tmp / "store", 9, swirled, store_extra);
  auto stored = StoredRun::open(tmp / "store/segment-000");
  Context ctx(parse_config(testing::small_config(replayed)));
  std::vector<double> xyz, values;
  for (std::size_t s = 0; s < stored->step_count(); ++s) {
    stored->read_points(s, xyz);
    MeshView view = stored->mesh();
    view.points = {reinterpret_cast<const std::byte*>(xyz.data()), view.point_count(), 3 * sizeof(double)};
    ctx.publish_mesh(view);
    stored->read("T", s, values);
    ctx.publish_field(fixtures::point_field("T", values), false);
    ctx.execute(stored->time(s), stored->cycle(s));
  }
  EXPECT_EQ(ctx.mesh_preparations(), 1u);
  EXPECT_EQ(ctx.geometry_updates(), 8u);
  ReplayDifference d;
  double sum = 0;
  std::size_t n = 0;
  for (std::size_t row = 1; row <= 18; ++row) {
    const auto a = image(db, row), b = image(replayed, row);
    EXPECT_EQ(a.size(), b.size());
    for (std::size_t i = 0; i < a.size() && i < b.size(); ++i) {
      const int e = std::abs(int(a[i]) - int(b[i]));
      d.worst = std::max(d.worst, e);
      sum += double(e) * e;
      d.over_two_levels += e > 2 ? 1 : 0;
      ++n;
    }
  }
  d.rms_pct = 100 * std::sqrt(sum / double(n)) / 255;
  d.over_two_levels /= double(n);
  return d;
}

TEST(MovingStore, ReplayMovesTheMeshWithTheStoredCoordinates) {
  const ReplayDifference exact = replay_difference(R"(, "coordinates": "lossless")");
  EXPECT_LE(exact.worst, 1);
  const ReplayDifference bounded = replay_difference("");
  EXPECT_LE(bounded.rms_pct, 0.25);
  EXPECT_LE(bounded.over_two_levels, 0.01) << "worst " << bounded.worst;
  EXPECT_GT(bounded.rms_pct, 0.0);  // the coordinates' error shows: the replay moved the mesh with them
}

TEST(MovingStore, ACorruptCoordinateRecordIsNamed) {
  TempDir tmp;
  run(tmp / "db", tmp / "store", 4, swirled, R"(, "coordinates": "lossless")");
  const std::string log = tmp / "store/segment-000/coordinates/exact.pnbc";
  {
    std::fstream f(log, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(24 + 8 + 100);  // inside the first record's coordinates
    f.put('\x7f');
  }
  auto stored = StoredRun::open(tmp / "store/segment-000");
  std::vector<double> xyz;
  try {
    stored->read_points(1, xyz);
    ADD_FAILURE() << "expected the corrupt record to be named";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::io_error);
    EXPECT_NE(std::string(e.what()).find("record 0"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("checksum"), std::string::npos) << e.what();
  }
}

TEST(MovingStore, CoordinatesConfigErrorsNameTheKey) {
  for (const auto& [value, needle] : std::vector<std::pair<std::string, std::string>>{
           {R"("exact")", "store.coordinates must be \"lossless\""},
           {R"({"altitude_fraction": 0.5})", "store.coordinates.altitude_fraction must be in (0, 0.125]"},
           {R"({"fraction": 0.1})", "store.coordinates.fraction is not a known key"}}) {
    try {
      parse_config(config("/tmp/unused", "/tmp/unused-store", R"(, "coordinates": )" + value));
      ADD_FAILURE() << value;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace penumbra::insitu

// SPDX-License-Identifier: BSD-3-Clause
// tests/unit/insitu/store_test.cpp -- the run's compressed history (config "store") and its
// read-back for re-rendering
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "config.h"
#include "context.h"
#include "fixtures/meshes.h"
#include "penumbra/core/error.h"
#include "penumbra/insitu/stored_run.h"
#include "stored_mesh.h"
#include "test_util.h"

namespace penumbra::insitu {
namespace {

using fixtures::BlockCells;
using testing::TempDir;

// A field moving through a block over time: x + 0.3 sin(t + 2y).
std::vector<double> wave(const fixtures::OwnedMesh& mesh, double t) {
  return fixtures::sample(mesh, [t](double x, double y, double z) { return x + 0.3 * std::sin(t + 2 * y) + 0.1 * z; });
}

std::string store_config(const std::string& db, const std::string& store, const std::string& extra = "") {
  return testing::small_config(db, R"([{"name": "T"}])",
                               R"(, "trigger": {"every_cycles": 5}, "store": {"directory": ")" + store +
                                   R"(", "window": 8)" + extra + "}");
}

TEST(Store, EveryStepIsKeptWithinTheBoundAndReadsBack) {
  TempDir tmp;
  const auto mesh = fixtures::block(BlockCells::hexes, 4, 3, 3, {0, 0, 0}, {1, 1, 1});
  const double bound = 1e-3;
  {
    Context ctx(parse_config(store_config(tmp / "db", tmp / "store", R"(, "error_bound": {"absolute": 0.001})")));
    ctx.publish_mesh(mesh.view());
    for (int step = 0; step < 21; ++step) {  // two full windows of 8 and a partial one of 5
      const auto v = wave(mesh, 0.1 * step);  // borrowed: must outlive execute
      ctx.publish_field(fixtures::point_field("T", v), false);
      ctx.execute(0.1 * step, step);
    }
    ctx.finalize();
  }
  auto run = StoredRun::open(tmp / "store/segment-000");
  ASSERT_EQ(run->step_count(), 21u);
  EXPECT_EQ(run->fields(), std::vector<std::string>{"T"});
  EXPECT_EQ(run->mesh().point_count(), mesh.point_count());
  EXPECT_EQ(run->mesh().cell_count(), mesh.cell_count());
  std::vector<float> values;
  for (std::size_t s = 0; s < run->step_count(); ++s) {
    EXPECT_EQ(run->cycle(s), static_cast<std::int64_t>(s));
    EXPECT_DOUBLE_EQ(run->time(s), 0.1 * static_cast<double>(s));
    run->read("T", s, values);
    const auto expect = wave(mesh, 0.1 * static_cast<double>(s));
    ASSERT_EQ(values.size(), expect.size());
    double worst = 0;
    for (std::size_t i = 0; i < values.size(); ++i) worst = std::max(worst, std::fabs(values[i] - expect[i]));
    // The bound holds at every value (plus float32 rounding of values near 1.5).
    EXPECT_LE(worst, bound + 2e-7) << "step " << s;
  }
  EXPECT_THROW(run->read("T", 21, values), Error);
  EXPECT_THROW(run->read("pressure", 0, values), Error);
}

TEST(Store, RecordsOnItsOwnCadenceAndRefusesNonFiniteSteps) {
  TempDir tmp;
  const auto mesh = fixtures::block(BlockCells::tets, 3, 3, 3, {0, 0, 0}, {1, 1, 1});
  {
    Context ctx(parse_config(store_config(tmp / "db", tmp / "store", R"(, "every_cycles": 2)")));
    ctx.publish_mesh(mesh.view());
    for (int step = 0; step < 6; ++step) {
      auto v = wave(mesh, step);
      if (step == 2) v[7] = std::nan("");
      ctx.publish_field(fixtures::point_field("T", v), false);
      if (step == 2) {
        // Rendering goes on; the store names what it refused.
        try {
          ctx.execute(step, step);
          ADD_FAILURE() << "expected the store to refuse a NaN";
        } catch (const Error& e) {
          EXPECT_NE(std::string(e.what()).find("store: field 'T' at cycle 2"), std::string::npos) << e.what();
          EXPECT_NE(std::string(e.what()).find("vertex 7"), std::string::npos) << e.what();
        }
      } else {
        ctx.execute(step, step);
      }
    }
    ctx.finalize();
  }
  auto run = StoredRun::open(tmp / "store/segment-000");
  ASSERT_EQ(run->step_count(), 2u);  // cycles 0 and 4; 2 was refused, odd cycles not recorded
  EXPECT_EQ(run->cycle(0), 0);
  EXPECT_EQ(run->cycle(1), 4);
}

TEST(Store, NewTopologyStartsANewSegment) {
  TempDir tmp;
  auto a = fixtures::block(BlockCells::tets, 2, 2, 2, {0, 0, 0}, {1, 1, 1});
  auto b = fixtures::block(BlockCells::tets, 3, 2, 2, {0, 0, 0}, {1, 1, 1});
  b.topology_version = 2;
  {
    Context ctx(parse_config(store_config(tmp / "db", tmp / "store")));
    ctx.publish_mesh(a.view());
    const auto va = wave(a, 0), vb = wave(b, 1);
    ctx.publish_field(fixtures::point_field("T", va), false);
    ctx.execute(0, 0);
    ctx.publish_mesh(b.view());
    ctx.publish_field(fixtures::point_field("T", vb), false);
    ctx.execute(1, 1);
    ctx.finalize();
  }
  EXPECT_EQ(StoredRun::open(tmp / "store/segment-000")->mesh().point_count(), a.point_count());
  EXPECT_EQ(StoredRun::open(tmp / "store/segment-001")->mesh().point_count(), b.point_count());
}

TEST(Store, CorruptAndTruncatedMeshFilesAreRefusedByName) {
  TempDir tmp;
  const auto mesh = fixtures::block(BlockCells::wedges, 2, 2, 2, {0, 0, 0}, {1, 1, 1});
  const std::string path = tmp / "mesh.pnbm";
  write_stored_mesh(path, copy_mesh(mesh.view()));
  const StoredMesh back = read_stored_mesh(path);
  EXPECT_EQ(back.xyz, mesh.xyz);
  EXPECT_EQ(back.types.size(), mesh.cell_count());
  std::ifstream in(path, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  auto expect_refused = [&](const std::string& content, const std::string& needle) {
    std::ofstream(path, std::ios::binary | std::ios::trunc) << content;
    try {
      read_stored_mesh(path);
      ADD_FAILURE() << "expected refusal: " << needle;
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ErrorCode::io_error);
      EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
  };
  // Every truncated prefix is refused.
  for (std::size_t n = 0; n < bytes.size(); n += 7) expect_refused(bytes.substr(0, n), "");
  std::string flipped = bytes;
  flipped[bytes.size() / 2] ^= 0x10;
  expect_refused(flipped, "checksum");
  expect_refused("not a mesh at all, just some text that is long enough", "not a Penumbra mesh file");
}

TEST(Store, ConfigErrorsNameTheirKeys) {
  auto expect_error = [](const std::string& store, const std::string& needle) {
    try {
      parse_config(testing::small_config("/tmp/unused", R"([{"name": "T"}])", R"(, "store": )" + store));
      ADD_FAILURE() << needle;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
  };
  expect_error(R"({})", "store.directory is required");
  expect_error(R"({"directory": "s", "window": 12})", "store.window must be a multiple of 8");
  expect_error(R"({"directory": "s", "error_bound": {"absolute": 1, "relative": 1}})", "store.error_bound must have exactly one");
  expect_error(R"({"directory": "s", "error_bound": {"relative": 0}})", "store.error_bound.relative must be > 0");
  expect_error(R"({"directory": "s", "codebook_size": 1000})", "store.codebook_size must be in [2, 256]");
  expect_error(R"({"directory": "s", "entropy_level": 20})", "store.entropy_level must be in [0, 19]");
  expect_error(R"({"directory": "s", "zfp": true})", "store.zfp is not a known key");
  const auto level = [](const std::string& store) {
    return parse_config(testing::small_config("/tmp/unused", R"([{"name": "T"}])", R"(, "store": )" + store))
        .store->codec.entropy_level;
  };
  EXPECT_EQ(level(R"({"directory": "s", "entropy_level": 0})"), 0);
  EXPECT_EQ(level(R"({"directory": "s", "entropy_level": 19})"), 19);
  EXPECT_EQ(level(R"({"directory": "s"})"), compression::CodecParams{}.entropy_level);
}

}  // namespace
}  // namespace penumbra::insitu

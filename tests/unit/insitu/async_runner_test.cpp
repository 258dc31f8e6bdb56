// SPDX-License-Identifier: BSD-3-Clause
// tests/unit/insitu/async_runner_test.cpp -- "async": the same database and store as a
// synchronous run, the solver's arrays free once execute returns, failures reported by the next
// call, steps skipped and counted when the worker is busy, contexts on several threads
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "async_runner.h"
#include "config.h"
#include "context.h"
#include "fixtures/meshes.h"
#include "penumbra/core/error.h"
#include "penumbra/insitu/stored_run.h"
#include "test_util.h"

namespace penumbra::insitu {
namespace {

namespace fs = std::filesystem;
using fixtures::BlockCells;
using testing::TempDir;

const fixtures::OwnedMesh& mesh() {
  static const fixtures::OwnedMesh m = fixtures::tet_block_with_hole(6);
  return m;
}

std::vector<double> wave(int step) {
  return fixtures::sample(mesh(), [step](double x, double y, double z) { return x + 0.3 * std::sin(0.7 * step + 3 * y) + z; });
}

std::string config(const std::string& dir, const std::string& extra) {
  return testing::small_config(dir + "/db", R"([{"name": "T"}])",
                               R"(, "trigger": {"every_cycles": 2}, "store": {"directory": ")" + dir +
                                   R"(/store", "window": 8})" + extra);
}

// Every file under `dir` by relative path, with its bytes.
std::map<std::string, std::string> files_under(const fs::path& dir) {
  std::map<std::string, std::string> out;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    if (e.is_regular_file() && e.path().filename() != "config.json")
      out[fs::relative(e.path(), dir).string()] = testing::read_text(e.path().string());
  return out;
}

// Every file under `sync` is under `async` with the same bytes, and no other; returns how many.
std::size_t expect_same_files(const fs::path& sync, const fs::path& async) {
  const auto sync_files = files_under(sync), async_files = files_under(async);
  EXPECT_EQ(sync_files.size(), async_files.size());
  for (const auto& [name, bytes] : sync_files) {
    const auto it = async_files.find(name);
    if (it == async_files.end()) {
      ADD_FAILURE() << name << " is missing";
      continue;
    }
    EXPECT_TRUE(it->second == bytes) << name << " differs";
  }
  return sync_files.size();
}

TEST(AsyncRunner, WritesWhatASynchronousRunWritesWhileTheSolverReusesItsArrays) {
  TempDir tmp;
  {
    Context sync(parse_config(config(tmp / "sync", "")));
    sync.publish_mesh(mesh().view());
    for (int k = 0; k < 9; ++k) {
      const auto v = wave(k);
      sync.publish_field(fixtures::point_field("T", v), false);
      sync.execute(0.1 * k, k);
    }
    sync.finalize();
  }
  {
    AsyncRunner async(std::make_unique<Context>(parse_config(config(tmp / "async", R"(, "async": true)"))), false);
    async.publish_mesh(mesh().view());
    std::vector<double> v;  // one array, overwritten every step as a solver's is
    for (int k = 0; k < 9; ++k) {
      v = wave(k);
      async.publish_field(fixtures::point_field("T", v), false);
      EXPECT_EQ(async.execute(0.1 * k, k), k % 2 == 0);
      std::fill(v.begin(), v.end(), std::nan(""));  // the step must have taken its copy
    }
    async.finalize();
    EXPECT_EQ(async.last_step().cycle, 8);
    EXPECT_EQ(async.skipped_steps(), 0);
  }
  EXPECT_GT(expect_same_files(tmp / "sync", tmp / "async"), 10u);
}

// A mesh whose points move every step (and once back where they were, and once while the
// previous step is still on the worker), published before each step's field.
fixtures::OwnedMesh moved_mesh(int step) {
  fixtures::OwnedMesh m = fixtures::block(BlockCells::hexes, 6, 6, 5, {0, 0, 0}, {1, 1, 1});
  if (step != 4) fixtures::swirl(m, {0.5, 0.5, 0}, 0.6, 0.05 * step);
  return m;
}

TEST(AsyncRunner, AMovingMeshHandsItsPointsToTheWorkerAndWritesWhatASynchronousRunWrites) {
  TempDir tmp;
  const std::string lit = R"(, "lighting": {"model": "light-volume", "level0_resolution": 24,
                                             "lights": [{"type": "directional", "direction": [1, 0.5, -1]}]})";
  const auto field = [](const fixtures::OwnedMesh& m, int k) {
    return fixtures::sample(m, [k](double x, double y, double z) { return x + 0.3 * std::sin(0.7 * k + 3 * y) + z; });
  };
  {
    Context sync(parse_config(config(tmp / "sync", lit)));
    for (int k = 0; k < 9; ++k) {
      const fixtures::OwnedMesh m = moved_mesh(k);
      sync.publish_mesh(m.view());
      const auto v = field(m, k);
      sync.publish_field(fixtures::point_field("T", v), false);
      sync.execute(0.1 * k, k);
    }
    sync.finalize();
  }
  {
    AsyncRunner async(std::make_unique<Context>(parse_config(config(tmp / "async", lit + R"(, "async": true)"))), false);
    for (int k = 0; k < 9; ++k) {
      fixtures::OwnedMesh m = moved_mesh(k);
      async.publish_mesh(m.view());
      const auto v = field(m, k);
      async.publish_field(fixtures::point_field("T", v), false);
      async.execute(0.1 * k, k);
      std::fill(m.xyz.begin(), m.xyz.end(), std::nan(""));  // the step must have taken its copy
    }
    async.finalize();
  }
  expect_same_files(tmp / "sync", tmp / "async");
}

TEST(AsyncRunner, AMotionThatInvertsACellIsTheNextCallsErrorAndTheRunGoesOn) {
  TempDir tmp;
  AsyncRunner async(std::make_unique<Context>(parse_config(config(tmp.path(), R"(, "async": true)"))), false);
  fixtures::OwnedMesh m = moved_mesh(0);
  async.publish_mesh(m.view());
  const auto v = fixtures::sample(m, [](double x, double, double) { return x; });
  async.publish_field(fixtures::point_field("T", v), false);
  EXPECT_TRUE(async.execute(0, 0));
  const std::size_t p = 3 + 7 * (3 + 7 * 2);  // an interior point pushed through its neighbours
  m.xyz[3 * p + 2] += 0.5;
  EXPECT_NO_THROW(async.publish_mesh(m.view()));  // handed over with the next step
  async.publish_field(fixtures::point_field("T", v), false);
  EXPECT_TRUE(async.execute(0.2, 2));
  m.xyz[3 * p + 2] -= 0.5;
  async.publish_mesh(m.view());
  async.publish_field(fixtures::point_field("T", v), false);
  try {
    async.execute(0.4, 4);
    ADD_FAILURE() << "the inverted cell of step 2 was not reported";
  } catch (const Error& e) {
    const std::string text = e.what();
    EXPECT_NE(text.find("by the points' motion"), std::string::npos) << text;
    EXPECT_NE(text.find("cycle 2, rendered asynchronously"), std::string::npos) << text;
  }
  EXPECT_NO_THROW(async.finalize());
  EXPECT_EQ(async.last_step().cycle, 4);
}

// A runner that rendered step 0 and was handed step 2 without its field T: step 2 fails on the worker.
std::unique_ptr<AsyncRunner> runner_with_a_failing_step(const std::string& dir, const std::vector<double>& v) {
  auto async = std::make_unique<AsyncRunner>(std::make_unique<Context>(parse_config(config(dir, R"(, "async": true)"))), false);
  async->publish_mesh(mesh().view());
  async->publish_field(fixtures::point_field("T", v), false);
  EXPECT_TRUE(async->execute(0, 0));
  EXPECT_TRUE(async->execute(0.2, 2));  // T not published: handed over all the same
  return async;
}

TEST(AsyncRunner, AWorkersFailureIsTheNextCallsStatusNamingItsCycle) {
  TempDir tmp;
  const auto v = wave(0);
  const auto async = runner_with_a_failing_step(tmp.path(), v);
  try {
    async->publish_field(fixtures::point_field("T", v), false);
    async->execute(0.3, 3);
    ADD_FAILURE() << "step 2's failure was not reported";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::invalid_operation);
    EXPECT_NE(std::string(e.what()).find("cycle 2, rendered asynchronously"), std::string::npos) << e.what();
  }
  async->publish_field(fixtures::point_field("T", v), false);
  EXPECT_TRUE(async->execute(0.4, 4));
  EXPECT_NO_THROW(async->finalize());
  EXPECT_EQ(async->last_step().cycle, 4);
}

TEST(AsyncRunner, ALastStepSaysWhetherItFailed) {
  TempDir tmp;
  const auto v = wave(0);
  const auto async = runner_with_a_failing_step(tmp.path(), v);
  EXPECT_THROW(async->finalize(), Error);
  EXPECT_EQ(async->last_step().cycle, 2);
  EXPECT_EQ(async->last_step().status, ErrorCode::invalid_operation);
}

TEST(AsyncRunner, SkipsStepsWhileTheWorkerIsBusyAndCountsThem) {
  TempDir tmp;
  const std::string c = testing::small_config(tmp / "db2", R"([{"name": "T"}])",
                                              R"(, "image": {"width": 160, "height": 160}, "async": {"backpressure": "skip"})");
  const Config parsed = parse_config(c);
  ASSERT_TRUE(parsed.async.skip_when_busy);
  AsyncRunner skipping(std::make_unique<Context>(parsed), parsed.async.skip_when_busy);
  skipping.publish_mesh(mesh().view());
  int handed = 0;
  for (int k = 0; k < 6; ++k) {
    const auto v = wave(k);
    skipping.publish_field(fixtures::point_field("T", v), false);
    handed += skipping.execute(k, k);  // back to back: the worker is rendering the last one
  }
  skipping.finalize();
  EXPECT_GE(skipping.skipped_steps(), 1);
  EXPECT_EQ(handed + skipping.skipped_steps(), 6);
  // The database lists exactly the handed-over steps, every listed image whole.
  std::ifstream csv(tmp / "db2/data.csv");
  std::string line;
  int rows = -1;
  while (std::getline(csv, line)) {
    ++rows;
    if (rows == 0) continue;
    const std::string file = line.substr(line.rfind(',') + 1);
    EXPECT_GT(fs::file_size(tmp / ("db2/" + file)), 0u) << file;
  }
  EXPECT_EQ(rows, 2 * handed);  // two cameras
}

TEST(AsyncRunner, ContextsOnSeveralThreadsAtOnce) {
  TempDir tmp;
  std::vector<std::thread> solvers;
  std::vector<int> rows(4, 0);
  for (int t = 0; t < 4; ++t)
    solvers.emplace_back([&, t] {
      const std::string dir = tmp / ("run" + std::to_string(t));
      AsyncRunner async(std::make_unique<Context>(parse_config(config(dir, R"(, "async": true)"))), false);
      async.publish_mesh(mesh().view());
      for (int k = 0; k < 5; ++k) {
        const auto v = wave(k + t);
        async.publish_field(fixtures::point_field("T", v), false);
        async.execute(k, k);
      }
      async.finalize();
      std::ifstream csv(dir + "/db/data.csv");
      std::string line;
      while (std::getline(csv, line)) ++rows[static_cast<std::size_t>(t)];
    });
  for (auto& s : solvers) s.join();
  for (int r : rows) EXPECT_EQ(r, 1 + 3 * 2);  // header, cycles 0, 2, 4 from two cameras
}

TEST(AsyncRunner, ConfigKeys) {
  EXPECT_FALSE(parse_config(testing::small_config("/tmp/x")).async.enabled);
  EXPECT_TRUE(parse_config(testing::small_config("/tmp/x", R"([{"name": "T"}])", R"(, "async": true)")).async.enabled);
  const Config c = parse_config(testing::small_config("/tmp/x", R"([{"name": "T"}])", R"(, "async": {"backpressure": "wait"})"));
  EXPECT_TRUE(c.async.enabled);
  EXPECT_FALSE(c.async.skip_when_busy);
  EXPECT_THROW(parse_config(testing::small_config("/tmp/x", R"([{"name": "T"}])", R"(, "async": {"backpressure": "drop"})")),
               Error);
  EXPECT_THROW(parse_config(testing::small_config("/tmp/x", R"([{"name": "T"}])", R"(, "async": 1)")), Error);
}

}  // namespace
}  // namespace penumbra::insitu

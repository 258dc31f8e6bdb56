// SPDX-License-Identifier: BSD-3-Clause
// tests/unit/insitu/progress_log_test.cpp -- "progress": a JSON line per rendered step whose
// stages add up, a failed step's line naming the failure, and a log that cannot be written
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "config.h"
#include "context.h"
#include "fixtures/meshes.h"
#include "penumbra/core/error.h"
#include "progress_log.h"
#include "test_util.h"

namespace penumbra::insitu {
namespace {

using fixtures::BlockCells;
using testing::TempDir;

std::string progress_config(const TempDir& tmp, const std::string& log) {
  return testing::small_config(tmp / "db", R"([{"name": "T"}])",
                               R"(, "trigger": {"every_cycles": 2}, "progress": {"log": ")" + log + R"(", "stderr_every": 2})");
}

std::vector<nlohmann::json> lines_of(const std::string& path) {
  std::vector<nlohmann::json> lines;
  std::ifstream in(path);
  for (std::string line; std::getline(in, line);) lines.push_back(nlohmann::json::parse(line));
  return lines;
}

std::uint64_t png_bytes_of_cycle(const std::string& db, int cycle) {
  char prefix[16];
  std::snprintf(prefix, sizeof prefix, "c%06d_", cycle);
  std::uint64_t bytes = 0;
  for (const auto& e : std::filesystem::recursive_directory_iterator(db))
    if (e.path().filename().string().rfind(prefix, 0) == 0) bytes += e.file_size();
  return bytes;
}

TEST(ProgressLog, OneLinePerRenderedStepWhoseStagesAddUp) {
  TempDir tmp;
  const auto mesh = fixtures::block(BlockCells::tets, 3, 3, 3, {0, 0, 0}, {1, 1, 1});
  const auto values = fixtures::sample(mesh, [](double x, double y, double z) { return x + y * z; });
  {
    Context ctx(parse_config(progress_config(tmp, tmp / "progress.jsonl")));
    ctx.publish_mesh(mesh.view());
    for (int cycle = 0; cycle < 5; ++cycle) {
      ctx.publish_field(fixtures::point_field("T", values), false);
      ctx.execute(0.5 * cycle, cycle);
    }
    // Cycle 6 renders without its field: the step fails, and its line says so.
    EXPECT_THROW(ctx.execute(3.0, 6), Error);
  }
  const auto lines = lines_of(tmp / "progress.jsonl");
  ASSERT_EQ(lines.size(), 4u);  // cycles 0, 2, 4 and the failed 6
  for (int i = 0; i < 3; ++i) {
    const auto& l = lines[static_cast<std::size_t>(i)];
    EXPECT_EQ(l["cycle"], 2 * i);
    EXPECT_DOUBLE_EQ(l["time"].get<double>(), 1.0 * i);
    EXPECT_EQ(l["images"], 2);  // two orbit cameras, one field
    EXPECT_EQ(l["fields"], nlohmann::json::array({"T"}));
    double stages = 0;
    for (const char* s : {"store", "gather", "light", "render", "composite", "write", "other"}) stages += l["ms"][s].get<double>();
    // Each stage is rounded to the microsecond in the log.
    EXPECT_NEAR(stages, l["ms"]["total"].get<double>(), 0.01);
    EXPECT_GT(l["ms"]["render"].get<double>(), 0);
    EXPECT_EQ(l["bytes_written"].get<std::uint64_t>(), png_bytes_of_cycle(tmp / "db", 2 * i));
    EXPECT_TRUE(l["failure"].is_null());
  }
  EXPECT_EQ(lines[3]["cycle"], 6);
  EXPECT_NE(lines[3]["failure"].get<std::string>().find("not published"), std::string::npos) << lines[3];
}

TEST(ProgressLog, ALogThatCannotBeOpenedOrWrittenIsAClearError) {
  TempDir tmp;
  try {
    Context ctx(parse_config(progress_config(tmp, tmp / "missing/dir/progress.jsonl")));
    ADD_FAILURE() << "a log in a missing directory was opened";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::io_error);
    EXPECT_NE(std::string(e.what()).find("progress log: cannot open"), std::string::npos) << e.what();
  }
  // A full disk: the step's images are written and listed, and the status names the log.
  const auto mesh = fixtures::block(BlockCells::tets, 2, 2, 2, {0, 0, 0}, {1, 1, 1});
  const auto values = fixtures::sample(mesh, [](double x, double, double) { return x; });
  Context ctx(parse_config(progress_config(tmp, "/dev/full")));
  ctx.publish_mesh(mesh.view());
  ctx.publish_field(fixtures::point_field("T", values), false);
  try {
    ctx.execute(0, 0);
    ADD_FAILURE() << "a log on a full disk was written";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::io_error);
    EXPECT_NE(std::string(e.what()).find("progress log: cannot write '/dev/full'"), std::string::npos) << e.what();
  }
  EXPECT_EQ(ctx.last_step().images, 2);
  EXPECT_GT(png_bytes_of_cycle(tmp / "db", 0), 0u);
}

TEST(ProgressLog, BadSettingsAreRefusedByName) {
  EXPECT_THROW(parse_config(testing::small_config("/tmp/x", R"([{"name": "T"}])", R"(, "progress": {"log": ""})")), Error);
  EXPECT_THROW(parse_config(testing::small_config("/tmp/x", R"([{"name": "T"}])", R"(, "progress": {"stderr_every": -1})")),
               Error);
  EXPECT_THROW(parse_config(testing::small_config("/tmp/x", R"([{"name": "T"}])", R"(, "progress": {"every": 1})")), Error);
}

}  // namespace
}  // namespace penumbra::insitu

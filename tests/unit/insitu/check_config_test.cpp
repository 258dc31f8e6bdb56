// SPDX-License-Identifier: BSD-3-Clause
// tests/unit/insitu/check_config_test.cpp -- pnb_check_config: the config checks of pnb_create,
// without creating anything
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "penumbra/penumbra.h"
#include "test_util.h"

namespace penumbra::insitu {
namespace {

namespace fs = std::filesystem;
using testing::TempDir;

std::string store_config(const TempDir& tmp) {
  return testing::small_config(tmp / "db", R"([{"name": "T"}])",
                               R"(, "store": {"directory": ")" + (tmp / "store") + R"(", "window": 8},
                                  "lighting": {"model": "occlusion", "occlusion": {"space": "image"}})");
}

TEST(CheckConfig, AGoodConfigIsOkAndNothingIsCreated) {
  TempDir tmp;
  EXPECT_EQ(pnb_check_config(store_config(tmp).c_str()), PNB_OK) << pnb_last_error(nullptr);
  EXPECT_TRUE(fs::is_empty(tmp.path()));  // neither the database nor the store directory
  // The same config in a file.
  const std::string path = tmp / "config.json";
  std::ofstream(path) << store_config(tmp);
  EXPECT_EQ(pnb_check_config(path.c_str()), PNB_OK) << pnb_last_error(nullptr);
  EXPECT_EQ(std::distance(fs::directory_iterator(tmp.path()), fs::directory_iterator()), 1);
}

TEST(CheckConfig, ABadConfigGivesTheStatusAndMessageOfPnbCreate) {
  TempDir tmp;
  const std::string db = tmp / "db";
  const char* const bad_fields[][2] = {
      {R"([{"name": "T", "colour": 1}])", "fields[0].colour is not a known key"},
      {R"([{"name": "T", "range": [1, 0]}])", "fields[0].range must have lo < hi"},
      {R"([])", "fields must be a non-empty array"},
  };
  for (const auto& [fields, expected] : bad_fields) {
    const std::string config = testing::small_config(db, fields);
    ASSERT_EQ(pnb_check_config(config.c_str()), PNB_INVALID_ARGUMENT) << fields;
    const std::string message = pnb_last_error(nullptr);
    EXPECT_NE(message.find(expected), std::string::npos) << message;
    pnb_context ctx = nullptr;
    EXPECT_EQ(pnb_create(config.c_str(), &ctx), PNB_INVALID_ARGUMENT);
    EXPECT_EQ(pnb_last_error(nullptr), message);
    EXPECT_EQ(ctx, nullptr);
  }
  EXPECT_EQ(pnb_check_config(R"({"output": )"), PNB_INVALID_ARGUMENT);
  EXPECT_NE(std::string(pnb_last_error(nullptr)).find("is not valid JSON"), std::string::npos);
  EXPECT_EQ(pnb_check_config(""), PNB_INVALID_ARGUMENT);
  EXPECT_NE(std::string(pnb_last_error(nullptr)).find("config: empty"), std::string::npos);
  EXPECT_EQ(pnb_check_config(nullptr), PNB_INVALID_ARGUMENT);
  EXPECT_NE(std::string(pnb_last_error(nullptr)).find("pnb_check_config: config is NULL"), std::string::npos);
  const std::string missing = tmp / "missing.json";
  EXPECT_EQ(pnb_check_config(missing.c_str()), PNB_IO_ERROR);
  EXPECT_NE(std::string(pnb_last_error(nullptr)).find(missing), std::string::npos);
  EXPECT_TRUE(fs::is_empty(tmp.path()));
}

TEST(CheckConfig, KeysNoBackendRunsTogetherAreRefusedAsByPnbCreate) {
  TempDir tmp;
  std::string config = store_config(tmp);
  config.insert(config.rfind('}'), R"(, "backend": "gpu")");
  ASSERT_EQ(pnb_check_config(config.c_str()), PNB_BACKEND_UNAVAILABLE);
  const std::string message = pnb_last_error(nullptr);
  EXPECT_NE(message.find("CPU backend only"), std::string::npos) << message;
  pnb_context ctx = nullptr;
  EXPECT_EQ(pnb_create(config.c_str(), &ctx), PNB_BACKEND_UNAVAILABLE);
  EXPECT_EQ(pnb_last_error(nullptr), message);
  EXPECT_TRUE(fs::is_empty(tmp.path()));
}

TEST(CheckConfig, TheMachineIsLeftToPnbCreate) {
  // A non-empty output directory without "resume" is the machine's state, not the config's.
  TempDir tmp;
  fs::create_directories(tmp / "db");
  std::ofstream(tmp / "db/other.txt") << "x";
  const std::string config = testing::small_config(tmp / "db");
  EXPECT_EQ(pnb_check_config(config.c_str()), PNB_OK) << pnb_last_error(nullptr);
  pnb_context ctx = nullptr;
  EXPECT_EQ(pnb_create(config.c_str(), &ctx), PNB_INVALID_ARGUMENT);
  EXPECT_NE(std::string(pnb_last_error(nullptr)).find("exists and is not empty"), std::string::npos);
}

}  // namespace
}  // namespace penumbra::insitu

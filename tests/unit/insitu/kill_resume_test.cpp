// SPDX-License-Identifier: BSD-3-Clause
// tests/unit/insitu/kill_resume_test.cpp -- a database left by a SIGKILLed solver is valid and resumable
#include <gtest/gtest.h>

#include <filesystem>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <thread>
#include <vector>

#include "cinema_database.h"
#include "database_checks.h"
#include "fixtures/meshes.h"
#include "penumbra/insitu/stored_run.h"
#include "penumbra/core/error.h"
#include "test_util.h"

extern char** environ;

namespace penumbra::insitu {
namespace {

using testing::TempDir;

/// Starts the helper solver; returns its pid.
pid_t spawn_solver(const std::string& dir, long first, long steps, const char* if_exists,
                   const std::string& store = "", bool moving = false, bool async = false) {
  const std::string f = std::to_string(first), s = std::to_string(steps);
  std::vector<const char*> argv{PNB_KILL_HELPER, dir.c_str(), f.c_str(), s.c_str(), if_exists};
  if (!store.empty()) argv.push_back(store.c_str());
  if (moving) argv.push_back("moving");
  if (async) argv.push_back("async");
  argv.push_back(nullptr);
  pid_t pid = -1;
  if (posix_spawn(&pid, PNB_KILL_HELPER, nullptr, nullptr, const_cast<char**>(argv.data()), environ) != 0) return -1;
  return pid;
}

int wait_exit(pid_t pid) {
  int status = 0;
  waitpid(pid, &status, 0);
  return status;
}

std::size_t listed_rows(const std::string& dir) {
  // data.csv is replaced by rename, so a read sees either the old or the new complete file.
  const auto table = CinemaDatabase::parse_csv(testing::read_text(dir + "/data.csv"), "data.csv");
  return table.empty() ? 0 : table.size() - 1;  // empty: not created yet
}

// Starts a solver with a store (moving points or not), SIGKILLs it once `steps` steps are listed
// (6 images each; at most a minute) and returns whether the kill ended it.
bool kill_after_steps(const std::string& dir, const std::string& store, bool moving, std::size_t steps, bool async = false) {
  const pid_t pid = spawn_solver(dir, 0, 100000, "error", store, moving, async);
  if (pid <= 0) return false;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (listed_rows(dir) < 6 * steps && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  kill(pid, SIGKILL);
  return WIFSIGNALED(wait_exit(pid));
}

// Kills the helper solver at several points of a step (right after a commit is seen and some time
// into the next), checks the database it left and resumes it.
void kill_and_resume(bool async) {
  TempDir tmp;
  for (int round = 0; round < 3; ++round) {
    const std::string dir = tmp / ("db" + std::to_string(round));
    const pid_t pid = spawn_solver(dir, 0, 100000, "error", "", false, async);
    ASSERT_GT(pid, 0);
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
    const std::size_t wanted = 6 * static_cast<std::size_t>(round + 1);  // 6 images per step
    while (listed_rows(dir) < wanted && std::chrono::steady_clock::now() < deadline)
      std::this_thread::sleep_for(std::chrono::microseconds(200));
    std::this_thread::sleep_for(std::chrono::microseconds(700 * round));
    kill(pid, SIGKILL);
    const int status = wait_exit(pid);
    ASSERT_TRUE(WIFSIGNALED(status)) << "the solver ended before it was killed";
    const auto table = testing::check_valid_database(dir);
    ASSERT_GE(table.size() - 1, wanted);
    EXPECT_EQ((table.size() - 1) % 6, 0u) << "a step was listed partially";

    // Resume: the same directory with if_exists "resume" appends later cycles.
    const long next = static_cast<long>((table.size() - 1) / 6);
    ASSERT_EQ(wait_exit(spawn_solver(dir, next, 2, "resume", "", false, async)), 0);
    const auto resumed = testing::check_valid_database(dir);
    ASSERT_EQ(resumed.size(), table.size() + 12);
    for (std::size_t r = 0; r < table.size(); ++r) EXPECT_EQ(resumed[r], table[r]) << "row " << r << " changed";
    testing::expect_no_temporaries(dir);
  }
}

TEST(KillSafety, DatabaseOfKilledSolverIsValidAndResumable) { kill_and_resume(false); }

// With "async" the kill lands while the worker writes: the database is as valid.
TEST(KillSafety, DatabaseOfAKilledAsynchronousSolverIsValidAndResumable) { kill_and_resume(true); }

TEST(KillSafety, StoreOfKilledSolverKeepsEveryFinishedWindow) {
  TempDir tmp;
  const std::string dir = tmp / "db", store = tmp / "store";
  // 20 rendered steps (6 images each): two windows of 8 are finished or being written.
  ASSERT_TRUE(kill_after_steps(dir, store, false, 20)) << "the solver ended before it was killed";
  const std::size_t rendered = listed_rows(dir) / 6;
  auto run = StoredRun::open(store + "/segment-000");
  EXPECT_EQ(run->fields(), (std::vector<std::string>{"T", "T2"}));
  // Whole windows only: at least the first one (the second may still have been in flight).
  EXPECT_GE(run->step_count(), 8u);
  EXPECT_EQ(run->step_count() % 8, 0u);
  EXPECT_LE(run->step_count(), rendered + 1);
  std::vector<float> values;
  for (std::size_t s = 0; s < run->step_count(); ++s) {
    EXPECT_EQ(run->cycle(s), static_cast<std::int64_t>(s));
    run->read("T", s, values);
    EXPECT_EQ(values.size(), run->mesh().point_count());
  }
}

// A Lagrangian run killed mid-window: its one segment reopens with the steps whose fields and
// coordinates are both whole, each step's points where the solver had them (within the bound).
void check_killed_moving_store(bool async) {
  TempDir tmp;
  const std::string dir = tmp / "db", store = tmp / "store";
  ASSERT_TRUE(kill_after_steps(dir, store, true, 20, async)) << "the solver ended before it was killed";
  EXPECT_FALSE(std::filesystem::exists(store + "/segment-001"));
  auto run = StoredRun::open(store + "/segment-000");
  ASSERT_TRUE(run->points_move());
  EXPECT_GE(run->step_count(), 8u);  // the first windows of the fields and of the coordinates
  const auto base = fixtures::block(fixtures::BlockCells::tets, 6, 6, 6, {0, 0, 0}, {1, 1, 1});
  std::vector<double> xyz;
  for (std::size_t s = 0; s < run->step_count(); ++s) {
    auto mesh = base;
    fixtures::swirl(mesh, {0.5, 0.5, 0}, 0.6, 0.01 * static_cast<double>(s));
    run->read_points(s, xyz);
    ASSERT_EQ(xyz.size(), mesh.xyz.size());
    double worst = 0;
    for (std::size_t i = 0; i < xyz.size(); ++i) worst = std::max(worst, std::fabs(xyz[i] - mesh.xyz[i]));
    EXPECT_LT(worst, 1e-2) << "step " << s;  // the bound: 1/16 of a 1/6-cube tet's altitude
  }
}

TEST(KillSafety, StoreOfAKilledMovingSolverReopens) { check_killed_moving_store(false); }

// Asynchronous, the moved points reach the worker with the step: the store is as whole.
TEST(KillSafety, StoreOfAKilledAsynchronousMovingSolverReopens) { check_killed_moving_store(true); }

TEST(KillSafety, ErrorModeRefusesTheLeftDatabase) {
  TempDir tmp;
  const std::string dir = tmp / "db";
  ASSERT_EQ(wait_exit(spawn_solver(dir, 0, 1, "error")), 0);
  const std::string before = testing::read_text(dir + "/data.csv");
  EXPECT_NE(wait_exit(spawn_solver(dir, 1, 1, "error")), 0);
  EXPECT_EQ(testing::read_text(dir + "/data.csv"), before);
}

}  // namespace
}  // namespace penumbra::insitu

// SPDX-License-Identifier: BSD-3-Clause
// tests/unit/insitu/full_disk_test.cpp -- a write that fails part way (a full disk) is a clear error
// through the API, and what was already written stays valid and resumable.
//
// The helper solver runs with a limit on the size of any file it writes (RLIMIT_FSIZE, SIGXFSZ
// ignored), so the write that would pass it fails with EFBIG at a repeatable point, as a write
// on a full disk fails with ENOSPC: the same failed write(2) reaches the same error paths.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>

#include "database_checks.h"
#include "penumbra/insitu/stored_run.h"
#include "test_util.h"

namespace penumbra::insitu {
namespace {

using testing::TempDir;

/// Runs the helper solver to its end with files limited to `max_file_bytes` (0: no limit) and its
/// standard error in `log`; returns the wait status.
int run_solver(const std::string& dir, long first, long steps, const char* if_exists, const std::string& store,
               rlim_t max_file_bytes, const std::string& log) {
  const std::string f = std::to_string(first), s = std::to_string(steps);
  const char* argv[] = {PNB_KILL_HELPER, dir.c_str(), f.c_str(), s.c_str(), if_exists,
                        store.empty() ? nullptr : store.c_str(), nullptr};
  const pid_t pid = fork();
  if (pid < 0) return -1;
  if (pid == 0) {
    // Only async-signal-safe calls until exec.
    const int fd = open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fd >= 0) dup2(fd, 2);
    signal(SIGXFSZ, SIG_IGN);
    if (max_file_bytes > 0) {
      const rlimit limit{max_file_bytes, max_file_bytes};
      setrlimit(RLIMIT_FSIZE, &limit);
    }
    execv(PNB_KILL_HELPER, const_cast<char**>(argv));
    _exit(127);
  }
  int status = 0;
  waitpid(pid, &status, 0);
  return status;
}

// Sizes at these settings: the stored mesh 61 KB, each field's history about 20 KB per window of 8
// steps, data.csv about 260 bytes per step, an image about 1 KB.
struct Limit {
  const char* what;
  rlim_t bytes;
  bool store;
};

void PrintTo(const Limit& limit, std::ostream* os) { *os << limit.what << " at " << limit.bytes << " bytes"; }

class FullDisk : public ::testing::TestWithParam<Limit> {};

TEST_P(FullDisk, FailedWriteIsAClearErrorAndKeepsWhatWasWritten) {
  TempDir tmp;
  const std::string dir = tmp / "db", store = GetParam().store ? tmp / "store" : std::string(), log = tmp / "stderr.txt";
  const int status = run_solver(dir, 0, 400, "error", store, GetParam().bytes, log);
  ASSERT_TRUE(WIFEXITED(status)) << "the solver was killed by a signal: " << (WIFSIGNALED(status) ? WTERMSIG(status) : 0);
  EXPECT_EQ(WEXITSTATUS(status), 1) << "the solver should have been told of the failed write";
  const std::string message = testing::read_text(log);
  EXPECT_FALSE(message.empty());
  EXPECT_TRUE(message.find("write") != std::string::npos || message.find("disk") != std::string::npos ||
              message.find("space") != std::string::npos || message.find("large") != std::string::npos)
      << message;

  // The database is valid: every listed image exists and decodes; whole steps only.
  const auto table = testing::check_valid_database(dir);
  ASSERT_FALSE(table.empty());
  EXPECT_GE(table.size() - 1, 6u) << "nothing was kept";
  EXPECT_LT(table.size() - 1, 6u * 400) << "the limit was never reached";
  EXPECT_EQ((table.size() - 1) % 6, 0u) << "a step was listed partially";
  testing::expect_no_temporaries(dir);

  // The compressed history keeps its finished windows, readable.
  if (!store.empty()) {
    auto run = StoredRun::open(store + "/segment-000");
    EXPECT_GE(run->step_count(), 8u) << "no finished window was kept";
    EXPECT_EQ(run->step_count() % 8, 0u);
    EXPECT_LE(run->step_count(), (table.size() - 1) / 6);
    std::vector<float> values;
    for (std::size_t s = 0; s < run->step_count(); ++s) {
      run->read("T", s, values);
      EXPECT_EQ(values.size(), run->mesh().point_count());
    }
  }

  // With room again, the run resumes after the last listed step and keeps every row.
  const long next = static_cast<long>((table.size() - 1) / 6);
  ASSERT_EQ(run_solver(dir, next, 2, "resume", store.empty() ? store : tmp / "store2", 0, log), 0)
      << testing::read_text(log);
  const auto resumed = testing::check_valid_database(dir);
  ASSERT_EQ(resumed.size(), table.size() + 12);
  for (std::size_t r = 0; r < table.size(); ++r) EXPECT_EQ(resumed[r], table[r]) << "row " << r << " changed";
  testing::expect_no_temporaries(dir);
}

INSTANTIATE_TEST_SUITE_P(Writes, FullDisk,
                         ::testing::Values(Limit{"history", 100 * 1024, true}, Limit{"index", 8 * 1024, false}),
                         [](const ::testing::TestParamInfo<Limit>& info) { return std::string(info.param.what); });

}  // namespace
}  // namespace penumbra::insitu

// SPDX-License-Identifier: BSD-3-Clause
// tests/unit/core/thread_pool_test.cpp
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <mutex>
#include <set>
#include <thread>
#include <stdexcept>
#include <vector>

#include <sys/wait.h>
#include <unistd.h>

#include "penumbra/core/thread_pool.h"

TEST(ThreadPool, CoversEveryIndexOnce) {
  std::vector<std::atomic<int>> hits(10007);
  penumbra::parallel_for(hits.size(), 64, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) ++hits[i];
  });
  for (auto& h : hits) ASSERT_EQ(h.load(), 1);
}

TEST(ThreadPool, RethrowsOnCaller) {
  EXPECT_THROW(penumbra::parallel_for(100, 1, [](std::size_t b, std::size_t) {
                 if (b == 50) throw std::runtime_error("boom");
               }),
               std::runtime_error);
}

TEST(ThreadPool, ASerialScopeKeepsEveryChunkOnItsThreadInOrderUntilItEnds) {
  const auto threads_used = [] {
    std::mutex m;
    std::set<std::thread::id> ids;
    std::vector<std::size_t> starts;
    penumbra::parallel_for(4096, 1, [&](std::size_t b, std::size_t) {
      std::this_thread::sleep_for(std::chrono::microseconds(b % 64 == 0 ? 200 : 0));  // room for a second thread
      std::lock_guard<std::mutex> lock(m);
      ids.insert(std::this_thread::get_id());
      starts.push_back(b);
    });
    EXPECT_EQ(starts.size(), 4096u);
    return std::make_pair(ids, std::is_sorted(starts.begin(), starts.end()));
  };
  {
    penumbra::SerialScope serial;
    {
      penumbra::SerialScope nested;
    }
    const auto [ids, in_order] = threads_used();  // the nested scope's end leaves this one in force
    EXPECT_EQ(ids, std::set<std::thread::id>{std::this_thread::get_id()});
    EXPECT_TRUE(in_order);
    // Another thread's calls are not affected.
    std::set<std::thread::id> other;
    std::thread([&] { other = threads_used().first; }).join();
    if (penumbra::worker_count() > 1) EXPECT_GT(other.size(), 1u);
  }
  if (penumbra::worker_count() > 1) EXPECT_GT(threads_used().first.size(), 1u);
}

TEST(ThreadPool, NestedCallsCompleteAndCoverEveryIndex) {
  // A body that calls parallel_for finds the kept workers busy with the outer job; the inner
  // call must still run (on threads of its own) rather than wait for them.
  std::vector<std::atomic<int>> hits(64 * 257);
  penumbra::parallel_for(64, 1, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i)
      penumbra::parallel_for(257, 16, [&](std::size_t ib, std::size_t ie) {
        for (std::size_t j = ib; j < ie; ++j) ++hits[i * 257 + j];
      });
  });
  for (auto& h : hits) ASSERT_EQ(h.load(), 1);
}

TEST(ThreadPool, ConcurrentCallersFromSeveralThreadsEachGetTheirWork) {
  // A background thread (an encoder, a pager) and the main thread call at the same time.
  constexpr int kCallers = 4, kCalls = 200;
  std::vector<std::atomic<long>> sums(kCallers);
  std::vector<std::thread> callers;
  for (int c = 0; c < kCallers; ++c)
    callers.emplace_back([&, c] {
      for (int k = 0; k < kCalls; ++k)
        penumbra::parallel_for(1000, 7, [&](std::size_t b, std::size_t e) {
          long s = 0;
          for (std::size_t i = b; i < e; ++i) s += static_cast<long>(i);
          sums[c] += s;
        });
    });
  for (auto& t : callers) t.join();
  for (auto& s : sums) EXPECT_EQ(s.load(), long(kCalls) * 999 * 1000 / 2);
}

TEST(ThreadPool, WorkersAreKeptBetweenCalls) {
  // A helper thread that ran chunks of several calls is a kept one: thread_local storage
  // starts afresh in every new thread, even one that reuses an old thread's id.
  if (penumbra::worker_count() < 2) GTEST_SKIP() << "one worker: nothing to keep";
  static thread_local int last_call = -1, calls_served = 0;
  const std::thread::id caller = std::this_thread::get_id();
  std::atomic<int> most_calls_on_a_helper{0};
  for (int k = 0; k < 20; ++k)
    penumbra::parallel_for(64, 1, [&](std::size_t, std::size_t) {
      std::this_thread::sleep_for(std::chrono::microseconds(50));
      if (std::this_thread::get_id() == caller || last_call == k) return;
      last_call = k;
      const int served = ++calls_served;
      int seen = most_calls_on_a_helper.load();
      while (served > seen && !most_calls_on_a_helper.compare_exchange_weak(seen, served)) {
      }
    });
  EXPECT_GT(most_calls_on_a_helper.load(), 1);
}

TEST(ThreadPool, AForkedChildStillRunsOnSeveralThreads) {
  // The child of a fork has none of the parent's kept workers: its calls must start threads of
  // their own rather than run every chunk on the caller (or wait for workers that do not exist).
  if (penumbra::worker_count() < 2) GTEST_SKIP() << "one worker: nothing to compare";
  penumbra::parallel_for(64, 1, [](std::size_t, std::size_t) {});  // the parent's pool exists
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    std::mutex m;
    std::set<std::thread::id> ids;
    penumbra::parallel_for(64, 1, [&](std::size_t, std::size_t) {
      std::this_thread::sleep_for(std::chrono::microseconds(200));
      std::lock_guard<std::mutex> lock(m);
      ids.insert(std::this_thread::get_id());
    });
    _exit(ids.size() > 1 ? 0 : 1);
  }
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0) << "the child ran every chunk on one thread";
}

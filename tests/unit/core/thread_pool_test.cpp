// tests/unit/core/thread_pool_test.cpp
#include <gtest/gtest.h>

#include <atomic>
#include <stdexcept>
#include <vector>

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

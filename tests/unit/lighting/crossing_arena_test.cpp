// SPDX-License-Identifier: BSD-3-Clause
// tests/unit/lighting/crossing_arena_test.cpp -- spans of walk crossings: disjoint, stable, reusable
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <thread>
#include <vector>

#include "lighting/crossing_arena.h"

namespace penumbra::render::lighting {
namespace {

TEST(CrossingArena, SpansAreDisjointAndKeepTheirContents) {
  CrossingArena arena;
  // Spans of many sizes, some larger than a block, from two threads at once; each filled with
  // its own tag. A span that overlapped another, or moved, would show another tag.
  constexpr int kSpans = 3000;
  std::vector<WalkCrossing*> spans(2 * kSpans);
  std::vector<std::size_t> sizes(2 * kSpans);
  auto fill = [&](int thread) {
    for (int i = 0; i < kSpans; ++i) {
      const std::size_t k = static_cast<std::size_t>(2 * i + thread);
      sizes[k] = i % 500 == 7 ? 200000 : 1 + static_cast<std::size_t>((i * 37) % 400);
      spans[k] = arena.allocate(sizes[k]);
      for (std::size_t j = 0; j < sizes[k]; ++j) spans[k][j].id[0] = static_cast<std::int32_t>(k);
    }
  };
  std::thread other(fill, 1);
  fill(0);
  other.join();
  for (std::size_t k = 0; k < spans.size(); ++k)
    for (std::size_t j = 0; j < sizes[k]; ++j) ASSERT_EQ(spans[k][j].id[0], static_cast<std::int32_t>(k)) << k;
  EXPECT_GE(arena.bytes(), 2 * 3000 * sizeof(WalkCrossing));
}

TEST(CrossingArena, ResetReusesTheBlocks) {
  CrossingArena arena;
  std::vector<std::size_t> sizes;
  for (int i = 0; i < 4000; ++i) sizes.push_back(i % 900 == 3 ? 150000 : 1 + static_cast<std::size_t>((i * 53) % 300));
  WalkCrossing* first = nullptr;
  for (std::size_t n : sizes) {
    WalkCrossing* span = arena.allocate(n);
    if (!first) first = span;
  }
  const std::size_t held = arena.bytes();
  arena.reset();
  EXPECT_EQ(arena.allocate(sizes[0]), first);
  for (std::size_t k = 1; k < sizes.size(); ++k) (void)arena.allocate(sizes[k]);
  EXPECT_EQ(arena.bytes(), held);  // the same spans again: no new block
}

// Reserved blocks hold the spans asked for later: no block is added until they are used up, and
// a reserve below what is held adds nothing.
TEST(CrossingArena, ReservedBlocksServeLaterSpans) {
  CrossingArena arena;
  arena.reserve(200000);
  const std::size_t held = arena.bytes();
  EXPECT_GE(held, 200000 * sizeof(WalkCrossing));
  std::size_t handed = 0;
  while (handed + 300 <= 150000) {
    WalkCrossing* span = arena.allocate(300);
    span[299].t = 1.0f;  // writable to its end
    handed += 300;
  }
  EXPECT_EQ(arena.bytes(), held);
  arena.reserve(1000);
  EXPECT_EQ(arena.bytes(), held);
  for (int i = 0; i < 1000; ++i) (void)arena.allocate(300);  // past the reserve: blocks added
  EXPECT_GT(arena.bytes(), held);
}

TEST(CrossingArena, MovedArenaKeepsItsSpans) {
  CrossingArena arena;
  WalkCrossing* span = arena.allocate(10);
  for (int j = 0; j < 10; ++j) span[j].t = static_cast<float>(j);
  CrossingArena moved(std::move(arena));
  for (int j = 0; j < 10; ++j) EXPECT_EQ(span[j].t, static_cast<float>(j));
  EXPECT_GT(moved.bytes(), 0u);
  EXPECT_EQ(arena.bytes(), 0u);  // NOLINT(bugprone-use-after-move): a moved-from arena is empty
  WalkCrossing* again = arena.allocate(5);  // and still usable
  EXPECT_NE(again, nullptr);
}

}  // namespace
}  // namespace penumbra::render::lighting

// SPDX-License-Identifier: BSD-3-Clause
// tests/unit/core/aligned_allocator_test.cpp -- blocks start on the boundary asked for, through
// growth, copies and element types of other sizes.
#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "penumbra/core/aligned_allocator.h"

namespace penumbra {
namespace {

template <class T>
bool on_64(const T* p) {
  return reinterpret_cast<std::uintptr_t>(p) % 64 == 0;
}

TEST(AlignedAllocator, EveryBlockStartsOnTheBoundary) {
  std::vector<std::uint32_t, AlignedAllocator<std::uint32_t, 64>> v;
  for (std::uint32_t i = 0; i < 5000; ++i) {
    v.push_back(i);
    ASSERT_TRUE(on_64(v.data())) << "after " << i + 1 << " elements";
  }
  const auto copy = v;
  EXPECT_TRUE(on_64(copy.data()));
  EXPECT_TRUE(copy == v);
  v.resize(3);
  v.shrink_to_fit();
  EXPECT_TRUE(on_64(v.data()));
  std::vector<std::uint8_t, AlignedAllocator<std::uint8_t, 64>> bytes(7);
  EXPECT_TRUE(on_64(bytes.data()));
}

TEST(AlignedAllocator, ASizeNoAllocationCanHoldThrows) {
  AlignedAllocator<std::uint64_t, 64> a;
  EXPECT_THROW((void)a.allocate(std::size_t(-1) / 4), std::bad_array_new_length);
}

}  // namespace
}  // namespace penumbra

// SPDX-License-Identifier: BSD-3-Clause
// render/src/lighting/crossing_arena.h -- storage for the crossings of one light's recorded walks
#pragma once
#include <cstddef>
#include <memory>
#include <mutex>
#include <vector>

#include "level1_walk.h"

namespace penumbra::render::lighting {

/// The crossings of every recorded walk of a light, in large blocks handed out in spans: a pass
/// takes one span per batch of walks under a lock, and a block's pages are touched in order as
/// it fills, where a list per walk would cost a malloc per vertex and a first touch of scattered
/// pages. Spans stay valid until reset(); blocks are never moved or freed before the arena is.
class CrossingArena {
public:
  CrossingArena() = default;
  CrossingArena(CrossingArena&&) noexcept;
  CrossingArena& operator=(CrossingArena&&) noexcept;
  ~CrossingArena();

  /// n contiguous crossings (n > 0), uninitialised. Thread-safe.
  WalkCrossing* allocate(std::size_t n);
  /// Blocks for at least n crossings in all, allocated now and their pages touched, so that
  /// walks recorded into them later do not pay for the first touch. Not thread-safe.
  void reserve(std::size_t n);
  /// Every span handed out is free again; the blocks are kept for the next walks.
  void reset();
  /// Bytes held by the blocks.
  std::size_t bytes() const;

private:
  struct Block {
    WalkCrossing* data;
    std::size_t size;  ///< crossings
    std::size_t bytes;
  };
  static Block new_block(std::size_t min_crossings);
  void release();

  std::unique_ptr<std::mutex> m_mutex = std::make_unique<std::mutex>();
  std::vector<Block> m_blocks;
  std::size_t m_block = 0;  ///< the block being filled
  std::size_t m_used = 0;   ///< crossings of it handed out
};

}  // namespace penumbra::render::lighting

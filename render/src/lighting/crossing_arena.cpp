// SPDX-License-Identifier: BSD-3-Clause
// render/src/lighting/crossing_arena.cpp -- blocks of walk crossings, handed out in spans
#include "crossing_arena.h"

#include <cstdlib>
#include <new>
#include <utility>


namespace penumbra::render::lighting {
namespace {

// Tens of thousands of crossings per block, on ordinary pages: huge pages make the kernel compact
// memory at first touch, which stalls level-1 batches by several ms.
constexpr std::size_t kBlockBytes = std::size_t{2} << 20;

}  // namespace

CrossingArena::CrossingArena(CrossingArena&& other) noexcept { *this = std::move(other); }

CrossingArena& CrossingArena::operator=(CrossingArena&& other) noexcept {
  if (this == &other) return *this;
  release();
  m_mutex = std::move(other.m_mutex);
  m_blocks = std::move(other.m_blocks);
  m_block = other.m_block;
  m_used = other.m_used;
  other.m_mutex = std::make_unique<std::mutex>();
  other.m_blocks.clear();
  other.m_block = other.m_used = 0;
  return *this;
}

CrossingArena::~CrossingArena() { release(); }

void CrossingArena::release() {
  for (const Block& b : m_blocks) std::free(b.data);
  m_blocks.clear();
  m_block = m_used = 0;
}

CrossingArena::Block CrossingArena::new_block(std::size_t min_crossings) {
  std::size_t bytes = kBlockBytes;
  while (bytes < min_crossings * sizeof(WalkCrossing)) bytes *= 2;
  void* data = std::malloc(bytes);
  if (!data) throw std::bad_alloc();
  return {static_cast<WalkCrossing*>(data), bytes / sizeof(WalkCrossing), bytes};
}

WalkCrossing* CrossingArena::allocate(std::size_t n) {
  std::lock_guard<std::mutex> lock(*m_mutex);
  // The rest of a block too small for the span is left unused: spans are a few hundred
  // crossings, blocks tens of thousands.
  while (m_block < m_blocks.size() && m_used + n > m_blocks[m_block].size) {
    ++m_block;
    m_used = 0;
  }
  if (m_block == m_blocks.size()) {
    m_blocks.push_back(new_block(n));
    m_used = 0;
  }
  WalkCrossing* span = m_blocks[m_block].data + m_used;
  m_used += n;
  return span;
}

void CrossingArena::reserve(std::size_t n) {
  std::size_t held = 0;
  for (const Block& b : m_blocks) held += b.size;
  while (held < n) {
    m_blocks.push_back(new_block(0));
    const Block& b = m_blocks.back();
    // A write per page faults it in (the contents stay undefined: spans are uninitialised).
    char* bytes = reinterpret_cast<char*>(b.data);
    for (std::size_t at = 0; at < b.bytes; at += 4096) bytes[at] = 0;
    held += b.size;
  }
}

void CrossingArena::reset() {
  std::lock_guard<std::mutex> lock(*m_mutex);
  m_block = m_used = 0;
}

std::size_t CrossingArena::bytes() const {
  std::size_t total = 0;
  for (const Block& b : m_blocks) total += b.bytes;
  return total;
}

}  // namespace penumbra::render::lighting

// SPDX-License-Identifier: BSD-3-Clause
// compression/src/huge_pages.h -- large arrays on transparent huge pages, faulted in ahead of use (private).
#pragma once
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace penumbra::compression::detail {

/// Asks the kernel to back the whole 2 MiB pages inside [p, p + bytes) with transparent huge
/// pages, for an array of several MiB not yet touched. Large arrays that malloc maps fresh (a
/// page load's, the encoder's window buffers) cost about 12 us per first touch of each 4 KiB page
/// on a virtual machine (256 MB: 0.78 s; advised, 0.02-0.47 s). Only advice: where huge pages are
/// off, or outside Linux, it does nothing.
inline void advise_huge_pages(const void* p, std::size_t bytes) {
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  constexpr std::uintptr_t kHuge = std::uintptr_t(2) << 20;
  if (bytes < 4 * kHuge) return;
  const std::uintptr_t at = reinterpret_cast<std::uintptr_t>(p);
  const std::uintptr_t begin = (at + kHuge - 1) & ~(kHuge - 1), end = (at + bytes) & ~(kHuge - 1);
  if (end > begin) ::madvise(reinterpret_cast<void*>(begin), end - begin, MADV_HUGEPAGE);
#else
  (void)p, (void)bytes;
#endif
}

/// Faults [p, p + bytes) in for writing without writing to it (Linux 5.14 and later:
/// MADV_POPULATE_WRITE), so that the first writes there later do not stop for the kernel; as it
/// stores nothing, another thread may write the same memory meanwhile. Works through it
/// `chunk` bytes at a time while keep_going() holds. Returns false where the kernel cannot
/// (nothing is done then).
template <class KeepGoing>
bool populate_for_writing(void* p, std::size_t bytes, std::size_t chunk, KeepGoing keep_going) {
#if defined(__linux__) && defined(MADV_POPULATE_WRITE)
  constexpr std::uintptr_t kPage = 4096;
  const std::uintptr_t begin = (reinterpret_cast<std::uintptr_t>(p) + kPage - 1) & ~(kPage - 1);
  const std::uintptr_t end = (reinterpret_cast<std::uintptr_t>(p) + bytes) & ~(kPage - 1);
  for (std::uintptr_t at = begin; at < end && keep_going(); at += chunk)
    if (::madvise(reinterpret_cast<void*>(at), std::min<std::uintptr_t>(chunk, end - at), MADV_POPULATE_WRITE) != 0)
      return false;
  return true;
#else
  (void)p, (void)bytes, (void)chunk, (void)keep_going;
  return false;
#endif
}

/// Reserves room for n elements in v, advised onto huge pages before anything touches it.
template <class T, class A>
void reserve_on_huge_pages(std::vector<T, A>& v, std::size_t n) {
  if (v.capacity() >= n) return;
  v.reserve(n);
  advise_huge_pages(v.data(), n * sizeof(T));
}

/// n elements left uninitialised, advised onto huge pages: no page is touched until written.
template <class T>
std::unique_ptr<T[]> uninitialised_on_huge_pages(std::size_t n) {
  auto a = std::make_unique_for_overwrite<T[]>(n);
  advise_huge_pages(a.get(), n * sizeof(T));
  return a;
}

}  // namespace penumbra::compression::detail

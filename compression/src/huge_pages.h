// compression/src/huge_pages.h -- room for a large array on transparent huge pages (private).
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace penumbra::compression::detail {

/// Reserves room for n elements in v and, for an array of several MiB, asks the kernel to back
/// it with transparent huge pages before anything touches it. A page load fills arrays of tens
/// or hundreds of MB that malloc maps fresh, and each first touch of a 4 KiB page cost about
/// 12 us on a virtual machine (256 MB: 0.78 s; advised, 0.02-0.47 s). Only advice: where huge
/// pages are off, or outside Linux, this is reserve.
template <class T, class A>
void reserve_on_huge_pages(std::vector<T, A>& v, std::size_t n) {
  if (v.capacity() >= n) return;
  v.reserve(n);
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  constexpr std::uintptr_t kHuge = std::uintptr_t(2) << 20;
  const std::size_t bytes = n * sizeof(T);
  if (bytes < 4 * kHuge) return;
  const std::uintptr_t at = reinterpret_cast<std::uintptr_t>(v.data());
  const std::uintptr_t begin = (at + kHuge - 1) & ~(kHuge - 1), end = (at + bytes) & ~(kHuge - 1);
  if (end > begin) ::madvise(reinterpret_cast<void*>(begin), end - begin, MADV_HUGEPAGE);
#endif
}

}  // namespace penumbra::compression::detail

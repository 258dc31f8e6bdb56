// SPDX-License-Identifier: BSD-3-Clause
// core/include/penumbra/core/aligned_allocator.h
#pragma once
#include <cstddef>
#include <new>

#include "penumbra/core/export.h"

PNB_PUBLIC_BEGIN

namespace penumbra {

/// An allocator whose blocks start on an `Align`-byte boundary, for arrays that vector code
/// loads a cache line at a time: a 64-byte load from a row that straddles two lines costs two.
template <class T, std::size_t Align>
struct AlignedAllocator {
  static_assert(Align >= alignof(T) && (Align & (Align - 1)) == 0, "Align: a power of two, at least alignof(T)");
  using value_type = T;
  // Spelled out: allocator_traits cannot rebind a template with a non-type parameter.
  template <class U>
  struct rebind {
    using other = AlignedAllocator<U, Align>;
  };

  AlignedAllocator() noexcept = default;
  template <class U>
  AlignedAllocator(const AlignedAllocator<U, Align>&) noexcept {}

  T* allocate(std::size_t n) {
    if (n > std::size_t(-1) / sizeof(T)) throw std::bad_array_new_length();
    return static_cast<T*>(::operator new(n * sizeof(T), std::align_val_t(Align)));
  }
  // The unsized form: clang before 19 declares the sized one only with -fsized-deallocation.
  void deallocate(T* p, std::size_t) noexcept { ::operator delete(p, std::align_val_t(Align)); }

  template <class U>
  bool operator==(const AlignedAllocator<U, Align>&) const noexcept {
    return true;
  }
};

}  // namespace penumbra

PNB_PUBLIC_END

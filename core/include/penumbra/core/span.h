// SPDX-License-Identifier: BSD-3-Clause
// core/include/penumbra/core/span.h
#pragma once
#include <cstddef>
#include <span>

#include "penumbra/core/export.h"

PNB_PUBLIC_BEGIN

namespace penumbra {
/// Penumbra is C++20; Span is std::span.
template <class T>
using Span = std::span<T>;
}  // namespace penumbra

PNB_PUBLIC_END

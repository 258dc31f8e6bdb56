// SPDX-License-Identifier: BSD-3-Clause
// core/include/penumbra/core/elapsed.h -- wall time since a point, in milliseconds
#pragma once
#include <chrono>

#include "penumbra/core/export.h"

PNB_PUBLIC_BEGIN

namespace penumbra {

/// Milliseconds on the steady clock since t0: what frame budgets, reports and benchmarks time.
inline double ms_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace penumbra

PNB_PUBLIC_END

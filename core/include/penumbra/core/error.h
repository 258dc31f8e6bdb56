// SPDX-License-Identifier: BSD-3-Clause
// core/include/penumbra/core/error.h
#pragma once
#include <stdexcept>
#include <string>

#include "penumbra/core/export.h"

PNB_PUBLIC_BEGIN

namespace penumbra {

/// Error categories; numerically equal to the C API's pnb_status values.
enum class ErrorCode : int {
  ok = 0,
  invalid_argument = 1,
  invalid_operation = 2,
  out_of_memory = 3,
  backend_unavailable = 4,
  internal_error = 5,
  io_error = 6,
};

/// The single exception type thrown by Penumbra's C++ core for bad input or failed I/O.
/// The message names the call, the argument, the offending value and what was expected.
class Error : public std::runtime_error {
public:
  Error(ErrorCode code, const std::string& message) : std::runtime_error(message), m_code(code) {}
  ErrorCode code() const noexcept { return m_code; }

private:
  ErrorCode m_code;
};

/// Throws Error{invalid_argument, message} when `condition` is false.
inline void require(bool condition, const std::string& message) {
  if (!condition) throw Error(ErrorCode::invalid_argument, message);
}

}  // namespace penumbra

PNB_PUBLIC_END

/// Internal invariant check; compiled out of release builds.
#ifdef NDEBUG
#define PNB_ASSERT(cond) ((void)0)
#else
#include <cassert>
#define PNB_ASSERT(cond) assert(cond)
#endif

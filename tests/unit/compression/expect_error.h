// SPDX-License-Identifier: BSD-3-Clause
// tests/unit/compression/expect_error.h -- a call must fail with a given Error code and message.
#pragma once
#include <gtest/gtest.h>

#include <initializer_list>
#include <string>

#include "penumbra/core/error.h"

namespace penumbra::compression::testing {

/// `call()` throws Error with `code`, and its message holds every one of `parts`; `what` names
/// the case in failure messages.
template <class Call>
void expect_error(Call&& call, ErrorCode code, std::initializer_list<std::string> parts, const std::string& what) {
  try {
    call();
    ADD_FAILURE() << what << ": accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), code) << what;
    for (const std::string& part : parts)
      EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << what << ": " << e.what();
  }
}

}  // namespace penumbra::compression::testing

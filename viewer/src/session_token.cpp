// SPDX-License-Identifier: BSD-3-Clause
// viewer/src/session_token.cpp -- random session tokens, compared in constant time
#include "session_token.h"

#include <random>

namespace penumbra::viewer {

std::string new_token() {
  std::random_device source;
  static const char digits[] = "0123456789abcdef";
  std::string token;
  for (int i = 0; i < 4; ++i) {
    const std::uint32_t word = source();
    for (int k = 0; k < 8; ++k) token.push_back(digits[(word >> (4 * k)) & 15u]);
  }
  return token;
}

bool same_token(const std::string& given, const std::string& token) {
  if (given.size() != token.size() || token.empty()) return false;
  unsigned char differ = 0;
  for (std::size_t i = 0; i < token.size(); ++i) differ |= static_cast<unsigned char>(given[i] ^ token[i]);
  return differ == 0;
}

}  // namespace penumbra::viewer

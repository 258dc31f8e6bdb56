// SPDX-License-Identifier: BSD-3-Clause
// adaptors/replay/main.cpp -- penumbra-replay CONFIG INPUT [--steps a:b] [--quiet]
#include <iostream>
#include <string>
#include <vector>

#include "replay.h"

int main(int argc, char** argv) {
  const std::vector<std::string> args(argv + 1, argv + argc);
  return penumbra::replay::run(args, std::cout, std::cerr);
}

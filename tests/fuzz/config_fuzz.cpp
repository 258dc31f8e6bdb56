// SPDX-License-Identifier: BSD-3-Clause
// tests/fuzz/config_fuzz.cpp -- the JSON config through pnb_check_config, the parse-only C entry
// point that checks exactly what pnb_create checks of a config without opening a database or a
// store: nothing is created or written, whatever the text says.
#include <cstdint>
#include <string>

#include "fuzz_util.h"
#include "penumbra/penumbra.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  // Text that does not start with '{' is a file path to pnb_check_config; only JSON text is
  // fuzzed (reading whatever path the fuzzer spells, /dev/zero included, would test the OS).
  const std::size_t first = text.find_first_not_of(" \t\n\v\f\r");
  if (first == std::string::npos || text[first] != '{') return 0;
  const pnb_status status = pnb_check_config(text.c_str());  // up to a NUL, as a C caller passes it
  const char* message = pnb_last_error(nullptr);
  switch (status) {
    case PNB_OK:
      break;
    case PNB_INVALID_ARGUMENT:
    case PNB_BACKEND_UNAVAILABLE:
      if (message[0] == '\0')
        penumbra::fuzz::fail("pnb_check_config failed with status " + std::to_string(status) + " and no message");
      break;
    default:
      // A config text can only be wrong, or ask for what no backend runs; anything else
      // (out of memory, an internal error, an I/O error without a file) is a bug.
      penumbra::fuzz::fail("pnb_check_config: unexpected status " + std::to_string(status) + ": " + message);
  }
  return 0;
}

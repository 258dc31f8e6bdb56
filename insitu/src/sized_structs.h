// SPDX-License-Identifier: BSD-3-Clause
// insitu/src/sized_structs.h -- the C API's structs, read and written at the size the caller
// was compiled with (their struct_size), so that older binaries keep working as members are added
#pragma once
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>

#include "penumbra/core/error.h"

namespace penumbra::insitu {

/// Throws Error(invalid_argument) unless `size` is that of some version of the struct: at least
/// `first_size` (the first layout with struct_size) and at most this build's.
inline void check_struct_size(std::uint32_t size, std::size_t first_size, std::size_t this_size, const std::string& call,
                              const std::string& type, const std::string& initialiser) {
  if (size == 0)
    throw Error(ErrorCode::invalid_argument,
                call + ": " + type + ".struct_size is 0: initialise the struct with " + initialiser + " (C) or the Fortran type's default");
  if (size < first_size || size > this_size)
    throw Error(ErrorCode::invalid_argument,
                call + ": " + type + ".struct_size is " + std::to_string(size) + ", not the size of any version of " + type +
                    " this library reads (" + std::to_string(first_size) + " to " + std::to_string(this_size) + " bytes)" +
                    (size > this_size ? "; the caller was built against a later Penumbra: link it with that version" : ""));
}

/// The caller's struct as this build's: the members its size holds, the later ones from `defaults`.
template <class T>
T read_sized(const T& caller, const T& defaults, std::size_t first_size, const std::string& call, const std::string& type,
             const std::string& initialiser) {
  check_struct_size(caller.struct_size, first_size, sizeof(T), call, type, initialiser);
  T out = defaults;
  std::memcpy(static_cast<void*>(&out), &caller, caller.struct_size);
  return out;
}

/// Writes the members of `value` that the caller's struct holds, keeping its struct_size.
template <class T>
void write_sized(const T& value, T* caller, std::size_t first_size, const std::string& call, const std::string& type,
                 const std::string& initialiser) {
  const std::uint32_t size = caller->struct_size;
  check_struct_size(size, first_size, sizeof(T), call, type, initialiser);
  std::memcpy(static_cast<void*>(caller), &value, size);
  caller->struct_size = size;
}

}  // namespace penumbra::insitu

// SPDX-License-Identifier: BSD-3-Clause
// viewer/src/session_token.h -- the per-session secret that grants access to a viewer
#pragma once
#include <string>

namespace penumbra::viewer {

/// 32 hexadecimal digits (128 bits) from the system's random source (std::random_device, which
/// reads the kernel's generator on Linux). On a shared login node every user reaches loopback:
/// the token, not the address, keeps others out.
std::string new_token();

/// Whether `given` equals `token`, in time that depends only on their lengths.
bool same_token(const std::string& given, const std::string& token);

}  // namespace penumbra::viewer

// SPDX-License-Identifier: BSD-3-Clause
// compression/src/version.cpp
#include "penumbra/compression/version.h"

namespace penumbra::compression {
// Anchors the library so it has an object file; the codec lands here.
int container_format_version() { return kContainerFormatVersion; }
}  // namespace penumbra::compression

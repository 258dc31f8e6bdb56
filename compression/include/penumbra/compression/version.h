// compression/include/penumbra/compression/version.h
#pragma once

namespace penumbra::compression {
/// Version of the compressed field-history container format this build writes.
constexpr int kContainerFormatVersion = 1;
}  // namespace penumbra::compression

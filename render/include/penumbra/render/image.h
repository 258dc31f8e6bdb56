// SPDX-License-Identifier: BSD-3-Clause
// render/include/penumbra/render/image.h
#pragma once
#include <string>
#include <vector>

#include "penumbra/core/export.h"

PNB_PUBLIC_BEGIN

namespace penumbra::render {

/// Row-major RGBA image, top row first, premultiplied alpha, linear float in [0,1].
struct Image {
  int width = 0;
  int height = 0;
  std::vector<float> rgba;
  Image() = default;
  Image(int w, int h) : width(w), height(h), rgba(static_cast<std::size_t>(w) * h * 4, 0.0f) {}
  float* pixel(int x, int y) { return &rgba[(static_cast<std::size_t>(y) * width + x) * 4]; }
  const float* pixel(int x, int y) const { return &rgba[(static_cast<std::size_t>(y) * width + x) * 4]; }
};

/// 8-bit RGB of `image` composited over `background` (rows top first), as stored in PNGs.
std::vector<unsigned char> to_rgb8(const Image& image, const float background[3]);

/// RMS difference of two equal-size 8-bit RGB buffers, in percent of 255.
double rms_difference_pct(const std::vector<unsigned char>& a, const std::vector<unsigned char>& b);

/// Writes 8-bit RGB to `path` as PNG atomically (temporary file in the same directory, then
/// rename); throws penumbra::Error(io_error) naming the path when it cannot be written.
void write_png(const std::string& path, const std::vector<unsigned char>& rgb, int width, int height);

/// 8-bit RGB as the bytes of a PNG file (for answers over a network); throws Error(io_error)
/// when libpng fails.
std::vector<unsigned char> encode_png(const std::vector<unsigned char>& rgb, int width, int height);

/// Reads an 8-bit RGB or RGBA PNG (alpha dropped); throws Error(io_error) on failure.
std::vector<unsigned char> read_png_rgb(const std::string& path, int& width, int& height);

}  // namespace penumbra::render

PNB_PUBLIC_END

// SPDX-License-Identifier: BSD-3-Clause
// insitu/src/step_stages.cpp -- the composite stage
#include "step_stages.h"

#include <algorithm>
#include <cmath>
#include <utility>

namespace penumbra::insitu {

ComposedImage composite_view(RenderedView&& view, const float background[3]) {
  ComposedImage out;
  out.field = view.field;
  out.camera = view.camera;
  out.width = view.output.image.width;
  out.height = view.output.image.height;
  out.rgb = render::to_rgb8(view.output.image, background);
  return out;
}

namespace {

/// Where output pixel `i` of `n_out` falls among `n_in` input pixels: the two neighbours and the
/// weight of the second.
struct Tap {
  int lo, hi;
  float w;
};

Tap tap(int i, int n_in, int n_out) {
  const double x = std::clamp((i + 0.5) * n_in / n_out - 0.5, 0.0, static_cast<double>(n_in - 1));
  const int lo = static_cast<int>(x);
  return {lo, std::min(lo + 1, n_in - 1), static_cast<float>(x - lo)};
}

}  // namespace

ComposedImage enlarged(const ComposedImage& image, int width, int height) {
  if (image.width == width && image.height == height) return image;
  ComposedImage out;
  out.field = image.field;
  out.camera = image.camera;
  out.width = width;
  out.height = height;
  out.rgb.resize(static_cast<std::size_t>(width) * height * 3);
  const auto at = [&image](int x, int y, int c) { return static_cast<float>(image.rgb[(static_cast<std::size_t>(y) * image.width + x) * 3 + c]); };
  for (int y = 0; y < height; ++y) {
    const Tap ty = tap(y, image.height, height);
    for (int x = 0; x < width; ++x) {
      const Tap tx = tap(x, image.width, width);
      for (int c = 0; c < 3; ++c) {
        const float top = at(tx.lo, ty.lo, c) + tx.w * (at(tx.hi, ty.lo, c) - at(tx.lo, ty.lo, c));
        const float bottom = at(tx.lo, ty.hi, c) + tx.w * (at(tx.hi, ty.hi, c) - at(tx.lo, ty.hi, c));
        out.rgb[(static_cast<std::size_t>(y) * width + x) * 3 + c] = static_cast<unsigned char>(std::lround(top + ty.w * (bottom - top)));
      }
    }
  }
  return out;
}

}  // namespace penumbra::insitu

// SPDX-License-Identifier: BSD-3-Clause
// insitu/src/step_stages.cpp -- the composite stage
#include "step_stages.h"

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

}  // namespace penumbra::insitu

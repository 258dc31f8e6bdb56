// SPDX-License-Identifier: BSD-3-Clause
// insitu/src/step_stages.h -- what the stages of one step hand each other
//
// A step runs: gather (each field's values in double, its range over the ranks, its normalised
// values: Context::gather_field, normalize_field) -> prepare (the mesh at publish time; each
// field's lighting: Context::prepare_lighting) -> render (one RenderedView per camera and field,
// through render::Renderer) -> composite (the ranks' runs merged, then the view over the
// background: Context::composite, composite_view) -> write (ImageWriter, on rank 0: PNG and
// database row; the database commit ends the step). Each stage takes the previous one's output
// by value, so that a stage can run elsewhere: on another thread, or across ranks.
#pragma once
#include <cstddef>
#include <string>
#include <vector>

#include "penumbra/render/renderer.h"

namespace penumbra::insitu {

/// The render stage's output: one field seen from one camera.
struct RenderedView {
  std::size_t field = 0;   ///< index of the config's field entry
  std::size_t camera = 0;  ///< index of the mesh's camera
  render::RenderOutput output;
};

/// The composite stage's output: the final 8-bit RGB image of one view, rows top first.
struct ComposedImage {
  std::size_t field = 0, camera = 0;
  int width = 0, height = 0;
  std::vector<unsigned char> rgb;
};

/// The composite stage of a process that renders whole views: the view's image over the
/// background colour.
ComposedImage composite_view(RenderedView&& view, const float background[3]);

/// `image` enlarged to width x height by bilinear interpolation between pixel centres: a view
/// rendered smaller to keep within a step's budget, written at the database's one image size.
ComposedImage enlarged(const ComposedImage& image, int width, int height);

}  // namespace penumbra::insitu

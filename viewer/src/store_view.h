// SPDX-License-Identifier: BSD-3-Clause
// viewer/src/store_view.h -- views a run never stored, rendered from its compressed history
#pragma once
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "penumbra/render/transfer_function.h"

namespace penumbra::viewer {

/// One view of the stored run: any stored step, any orbit angle and zoom, the run's transfer
/// function or another one.
struct ViewRequest {
  std::size_t step = 0;   ///< counted through the store's segments in order
  std::size_t field = 0;  ///< index into StoreInfo::fields (the run config's field entries)
  double phi = 0, theta = 0;  ///< degrees, as the database's orbit columns
  double zoom = 1;            ///< > 1 comes closer (narrows the field of view)
  /// x and opacity in the units of the config's field entry; nullopt: the run's own.
  std::optional<render::TransferFunction> transfer_function;
  bool lit = true;  ///< the run's lighting, or none
};

/// What the page needs to ask for views.
struct StoreInfo {
  std::vector<double> times;
  std::vector<std::int64_t> cycles;
  std::vector<std::string> fields;  ///< the database's `field` values, per config field entry
  std::vector<render::TransferFunction> transfer_functions;  ///< the run's, per field entry
  std::string lighting;  ///< the database's `lighting` value ("none" without lighting)
  int width = 0, height = 0;
  double fov_y_deg = 30;
};

/// A rendered view, with the time each part took.
struct RenderedView {
  std::vector<unsigned char> png;
  double load_ms = 0;    ///< the step's field (and points) read through the pager
  double light_ms = 0;   ///< the lighting prepared for the field and transfer function
  double render_ms = 0;  ///< ray casting, compositing and PNG encoding
  bool light_converged = true;
};

/// Renders views of a stored run (a store directory or one segment, serial or written over
/// ranks) with the run's config (its fields, transfer functions, lighting, image size and
/// background: `config`, a path or JSON text, or when empty the config.json the store keeps), on
/// the CPU ray caster. Keeps the prepared mesh of the segment in use, the last
/// step's field values and each field's lighting: a new camera re-renders only; a new step or
/// transfer function solves the light again from the last solution (warm start). Not thread-safe:
/// one caller at a time (RenderQueue). Throws penumbra::Error naming what is wrong.
class StoreView {
public:
  StoreView(const std::string& store, const std::string& config);
  ~StoreView();
  StoreView(const StoreView&) = delete;
  StoreView& operator=(const StoreView&) = delete;

  const StoreInfo& info() const;
  RenderedView render(const ViewRequest& request);

private:
  struct Impl;
  std::unique_ptr<Impl> m_impl;
};

}  // namespace penumbra::viewer

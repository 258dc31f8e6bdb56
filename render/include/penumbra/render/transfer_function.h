// SPDX-License-Identifier: BSD-3-Clause
// render/include/penumbra/render/transfer_function.h
#pragma once
#include <vector>

#include "penumbra/core/vec3.h"

#include "penumbra/core/export.h"

PNB_PUBLIC_BEGIN

namespace penumbra::render {

/// A colour control point: data value x and linear RGB in [0,1].
struct ColorPoint { double x, r, g, b; };
/// An opacity control point: data value x and extinction coefficient per unit length (>= 0).
struct OpacityPoint { double x, a; };

/// Piecewise-linear transfer function over data values, clamped beyond its end points.
///
/// Optical model (emission-absorption): opacity is an extinction rate tau(s) per world unit
/// (as VTK's unstructured integrators use it) and a sample emits colour(s) * tau(s). Values
/// carrying NaN are "no data" and have zero extinction.
struct TransferFunction {
  std::vector<ColorPoint> colors;       ///< sorted by x, at least one
  std::vector<OpacityPoint> opacities;  ///< sorted by x, at least one

  Vec3d color(double s) const;
  double extinction(double s) const;
  /// Sorted, unique x of all control points: between two of them both colour and extinction
  /// are linear in s.
  std::vector<double> breakpoints() const;
  /// Throws penumbra::Error(invalid_argument) if empty, unsorted, non-finite or negative.
  void validate() const;
  /// Moves every control point's x from data units to the normalised units of a field mapped
  /// from [lo, hi] to [0, 1] (normalize_value, in double), as renderers see such a field.
  void normalize_x(double lo, double hi);
};

}  // namespace penumbra::render

PNB_PUBLIC_END

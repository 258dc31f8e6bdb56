// SPDX-License-Identifier: BSD-3-Clause
// insitu/src/field_stages.h -- one field's values, transfer function and shading in a step, as the
// in-situ context makes them and as a later renderer of the same run's store makes them again
#pragma once
#include <string>
#include <utility>
#include <vector>

#include "config.h"
#include "penumbra/render/shading.h"
#include "penumbra/render/transfer_function.h"

namespace penumbra::insitu {

/// The `lighting` column's value.
std::string lighting_label(const LightingConfig& l);

/// Whether the config lights its samples (a lighting model other than none).
bool lit(const Config& c);

/// Shading of a frame; `light_rgb` is the light volume's field for model light-volume.
render::Shading shading_of(const LightingConfig& l, const std::vector<float>* light_rgb);

/// The `field` column per config entry: the field name, made unique with the component when
/// one field is rendered several ways.
std::vector<std::string> field_labels(const Config& c);

/// The data range of field `f` on this rank's values, before the ranks agree on it: the config's
/// range, else the values' finite range (empty, lo > hi, when none is finite).
std::pair<double, double> local_range(const FieldConfig& f, const std::vector<double>& values);

/// The data range a field maps to [0, 1]: `lo`..`hi`, or a range widened around a constant
/// field's value, or around 0 when no value is finite.
std::pair<double, double> usable_range(double lo, double hi);

/// Transfer function of `f` over the step's normalised values (x in [0, 1] over [lo, hi]) with
/// extinction per world unit.
render::TransferFunction resolve_transfer_function(const FieldConfig& f, double lo, double hi, double diagonal);

}  // namespace penumbra::insitu

// SPDX-License-Identifier: BSD-3-Clause
// insitu/src/rank_lighting.h -- one light volume over every rank's cells
#pragma once
#include "penumbra/render/light_volume.h"
#include "rank_group.h"

namespace penumbra::insitu {

/// The ranks' level-0 grids merged (LightVolume::combine_level0): the element-wise maximum of the
/// extinction and of the mask over the ranks. Collective; throws Error(internal_error) on every
/// rank when their grids differ in size (they are made from the same global bounds, resolution
/// and lights, so they never should).
render::LightVolume::Level0Combine level0_merge(RankGroup& group);

}  // namespace penumbra::insitu

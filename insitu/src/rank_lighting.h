// SPDX-License-Identifier: BSD-3-Clause
// insitu/src/rank_lighting.h -- one light volume over every rank's cells
#pragma once
#include <cstdint>
#include <vector>

#include "penumbra/render/light_volume.h"
#include "penumbra/render/occlusion.h"
#include "rank_group.h"

namespace penumbra::insitu {

/// The ranks' level-0 grids merged (LightVolume::combine_level0): the element-wise maximum of the
/// extinction and of the mask over the ranks. Collective; throws Error(internal_error) on every
/// rank when their grids differ in size (they are made from the same global bounds, resolution
/// and lights, so they never should).
render::LightVolume::Level0Combine level0_merge(RankGroup& group);

/// The ranks' extinction grids of cone-traced occlusion merged the same way
/// (OcclusionLighting::combine_extinction). Collective; throws like level0_merge.
render::OcclusionLighting::ExtinctionCombine extinction_merge(RankGroup& group);

/// Shadow gaps that leave this rank's cells (OcclusionLighting::open_gaps), addressed to the
/// ranks whose bounds the segment's box meets: `requests[r]` for RankGroup::exchange (7 values per
/// segment), `sent[r]` the segments' places in the list.
struct GapRoutes {
  std::vector<std::vector<double>> requests;
  std::vector<std::vector<std::uint32_t>> sent;
};
/// `boxes`: every rank's bounds, 6 values each (RankGroup::all_gather).
GapRoutes route_gaps(const RankGroup& group, const std::vector<double>& boxes, const std::vector<render::GapSegment>& open);
/// The depth of every segment other ranks asked about, through this rank's cells.
std::vector<std::vector<double>> answer_gaps(const render::OcclusionLighting& occlusion,
                                             const std::vector<std::vector<double>>& asked);
/// Per open gap, the depths the other ranks answered, summed in rank order.
std::vector<double> sum_gap_answers(const GapRoutes& routes, const std::vector<std::vector<double>>& answered,
                                    std::size_t open);

}  // namespace penumbra::insitu

// SPDX-License-Identifier: BSD-3-Clause
// insitu/src/rank_lighting.cpp -- the ranks' level-0 grids merged into the whole mesh's
#include "rank_lighting.h"

#include <string>

#include "penumbra/core/error.h"

namespace penumbra::insitu {

render::LightVolume::Level0Combine level0_merge(RankGroup& group) {
  return [&group](std::vector<float>& tau, std::vector<render::Level0Mask>& mask) {
    // The reductions below must be the same size on every rank: agreed first.
    const auto n = static_cast<double>(tau.size());
    double sizes[2] = {n, -n};
    group.minimum(sizes, 2);
    if (sizes[0] != -sizes[1])
      throw Error(ErrorCode::internal_error, "light volume: the ranks' level-0 grids have between " +
                                                 std::to_string(sizes[0]) + " and " + std::to_string(-sizes[1]) +
                                                 " nodes; expected one grid over the global bounds");
    static_assert(sizeof(render::Level0Mask) == 1);
    group.maximum(tau.data(), tau.size());
    group.maximum(reinterpret_cast<std::uint8_t*>(mask.data()), mask.size());
  };
}

}  // namespace penumbra::insitu

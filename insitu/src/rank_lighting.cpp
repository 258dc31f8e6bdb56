// SPDX-License-Identifier: BSD-3-Clause
// insitu/src/rank_lighting.cpp -- the ranks' extinction grids merged into the whole mesh's
#include "rank_lighting.h"

#include <string>

#include "penumbra/core/error.h"

namespace penumbra::insitu {

namespace {

// The reductions that follow must be the same size on every rank: agreed first.
void agree_on_size(RankGroup& group, std::size_t size, const char* what) {
  const auto n = static_cast<double>(size);
  double sizes[2] = {n, -n};
  group.minimum(sizes, 2);
  if (sizes[0] != -sizes[1])
    throw Error(ErrorCode::internal_error, std::string(what) + ": the ranks' grids have between " +
                                               std::to_string(sizes[0]) + " and " + std::to_string(-sizes[1]) +
                                               " nodes; expected one grid over the global bounds");
}

}  // namespace

render::LightVolume::Level0Combine level0_merge(RankGroup& group) {
  return [&group](std::vector<float>& tau, std::vector<render::Level0Mask>& mask) {
    agree_on_size(group, tau.size(), "light volume");
    static_assert(sizeof(render::Level0Mask) == 1);
    group.maximum(tau.data(), tau.size());
    group.maximum(reinterpret_cast<std::uint8_t*>(mask.data()), mask.size());
  };
}

render::OcclusionLighting::ExtinctionCombine extinction_merge(RankGroup& group) {
  return [&group](std::vector<float>& tau) {
    agree_on_size(group, tau.size(), "occlusion");
    group.maximum(tau.data(), tau.size());
  };
}

namespace {

bool boxes_meet(const double* box, const Vec3d& lo, const Vec3d& hi) {
  return lo.x <= box[3] && lo.y <= box[4] && lo.z <= box[5] && hi.x >= box[0] && hi.y >= box[1] && hi.z >= box[2];
}

}  // namespace

GapRoutes route_gaps(const RankGroup& group, const std::vector<double>& boxes, const std::vector<render::GapSegment>& open) {
  const auto ranks = static_cast<std::size_t>(group.size());
  GapRoutes routes{std::vector<std::vector<double>>(ranks), std::vector<std::vector<std::uint32_t>>(ranks)};
  for (std::size_t i = 0; i < open.size(); ++i) {
    const render::GapSegment& g = open[i];
    const Vec3d end = g.start + g.direction * (g.length / length(g.direction));
    const Vec3d lo = min(g.start, end), hi = max(g.start, end);
    for (std::size_t r = 0; r < ranks; ++r) {
      if (static_cast<int>(r) == group.rank() || !boxes_meet(&boxes[6 * r], lo, hi)) continue;
      routes.requests[r].insert(routes.requests[r].end(), {g.start.x, g.start.y, g.start.z, g.direction.x, g.direction.y,
                                                           g.direction.z, g.length});
      routes.sent[r].push_back(static_cast<std::uint32_t>(i));
    }
  }
  return routes;
}

std::vector<std::vector<double>> answer_gaps(const render::OcclusionLighting& occlusion,
                                             const std::vector<std::vector<double>>& asked) {
  std::vector<std::vector<double>> answers(asked.size());
  for (std::size_t r = 0; r < asked.size(); ++r) {
    std::vector<render::GapSegment> segments(asked[r].size() / 7);
    for (std::size_t i = 0; i < segments.size(); ++i) {
      const double* v = &asked[r][7 * i];
      segments[i] = {{v[0], v[1], v[2]}, {v[3], v[4], v[5]}, v[6]};
    }
    answers[r] = occlusion.gap_depths(segments);
  }
  return answers;
}

std::vector<double> sum_gap_answers(const GapRoutes& routes, const std::vector<std::vector<double>>& answered,
                                    std::size_t open) {
  std::vector<double> extra(open, 0.0);
  for (std::size_t r = 0; r < routes.sent.size(); ++r) {
    require(answered[r].size() == routes.sent[r].size(),
            "shadow gaps: rank " + std::to_string(r) + " answered " + std::to_string(answered[r].size()) + " of " +
                std::to_string(routes.sent[r].size()) + " segments");
    for (std::size_t j = 0; j < routes.sent[r].size(); ++j) extra[routes.sent[r][j]] += answered[r][j];
  }
  return extra;
}

}  // namespace penumbra::insitu

// render/src/tet_order.cpp -- Morton order of tet centroids
#include "tet_order.h"

#include <algorithm>
#include <utility>

#include "penumbra/core/morton.h"
#include "penumbra/core/thread_pool.h"

namespace penumbra::render::detail {

std::vector<std::int32_t> morton_order(const TetMesh& m) {
  const Vec3d lo = m.bounds.lo, ext = m.bounds.hi - m.bounds.lo;
  double scale[3];
  for (int a = 0; a < 3; ++a) scale[a] = ext[a] > 0 ? 2097151.0 / ext[a] : 0.0;
  std::vector<std::pair<std::uint64_t, std::int32_t>> keyed(m.tets.size());
  parallel_for(keyed.size(), 1 << 14, [&](std::size_t b, std::size_t e) {
    for (std::size_t t = b; t < e; ++t) {
      Vec3d c{0, 0, 0};
      for (int k = 0; k < 4; ++k) c = c + m.points[static_cast<std::size_t>(m.tets[t][k])];
      std::uint64_t code = 0;
      for (int a = 0; a < 3; ++a) {
        const double g = std::clamp((c[a] * 0.25 - lo[a]) * scale[a], 0.0, 2097151.0);
        code |= spread_bits_3d(static_cast<std::uint64_t>(g)) << a;
      }
      keyed[t] = {code, static_cast<std::int32_t>(t)};
    }
  });
  std::sort(keyed.begin(), keyed.end());
  std::vector<std::int32_t> order(keyed.size());
  for (std::size_t i = 0; i < keyed.size(); ++i) order[i] = keyed[i].second;
  return order;
}

}  // namespace penumbra::render::detail

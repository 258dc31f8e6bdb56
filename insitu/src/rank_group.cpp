// SPDX-License-Identifier: BSD-3-Clause
// insitu/src/rank_group.cpp -- the serial group, and what the ranks agree on through minimum()
#include "rank_group.h"

#include <vector>

namespace penumbra::insitu {
namespace {

class SerialGroup final : public RankGroup {
public:
  int rank() const override { return 0; }
  int size() const override { return 1; }
  std::vector<Failure> failures(int code, const std::string& message) override {
    if (code == 0) return {};
    return {Failure{0, code, message}};
  }
  void minimum(double*, int) override {}
  void maximum(float*, std::size_t) override {}
  void maximum(std::uint8_t*, std::size_t) override {}
  std::vector<double> all_gather(const std::vector<double>& mine) override { return mine; }
  std::vector<std::vector<double>> exchange(const std::vector<std::vector<double>>& to_each) override { return to_each; }
  render::Image composite(const render::RayRuns&, int width, int height) override {
    // A serial run composites whole views itself (composite_view); runs are never asked for.
    return render::Image(width, height);
  }
  std::shared_ptr<RankGroup> duplicate() override { return std::make_shared<SerialGroup>(); }
  std::string threads_refused() const override { return {}; }
};

}  // namespace

std::shared_ptr<RankGroup> serial_group() { return std::make_shared<SerialGroup>(); }

Bounds global_bounds(RankGroup& group, const Bounds& mine) {
  // max(x) = -min(-x): one reduction for both corners.
  double v[6] = {mine.lo.x, mine.lo.y, mine.lo.z, -mine.hi.x, -mine.hi.y, -mine.hi.z};
  group.minimum(v, 6);
  Bounds b;
  b.lo = {v[0], v[1], v[2]};
  b.hi = {-v[3], -v[4], -v[5]};
  return b;
}

void global_range(RankGroup& group, double& lo, double& hi) {
  double v[2] = {lo, -hi};
  group.minimum(v, 2);
  lo = v[0];
  hi = -v[1];
}

}  // namespace penumbra::insitu

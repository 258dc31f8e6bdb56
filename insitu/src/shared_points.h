// SPDX-License-Identifier: BSD-3-Clause
// insitu/src/shared_points.h -- the points a rank shares with others, and one light for each of them
#pragma once
#include <array>
#include <cstdint>
#include <vector>

#include "penumbra/render/light_volume.h"
#include "penumbra/render/tet_mesh.h"
#include "rank_group.h"

namespace penumbra::insitu {

/// The points on this rank's partition boundary that other ranks hold too: every rank that uses
/// a point on a partition boundary publishes its own copy, at the same coordinates. They are found
/// once per mesh among the points of each rank's unmatched faces, sent to the ranks whose bounds
/// hold them and matched by their exact coordinates; each pair of ranks then lists the points it
/// shares in the same (coordinate) order, so that values travel without ids. Ranks that share no
/// point exchange nothing.
class SharedPoints {
public:
  /// Collective. `lights` are the light volume's, in its order.
  SharedPoints(RankGroup& group, const render::TetMesh& mesh, const std::vector<render::Light>& lights);

  /// Points this rank shares with at least one other.
  std::size_t size() const { return m_points.size(); }
  /// Ranks this one shares points with.
  std::size_t peers() const { return m_peers.size(); }

  /// One light per shared point, the same on every rank that holds it, in three steps so that
  /// only the exchange is collective: messages() for the other ranks, RankGroup::exchange, then
  /// settle() with what came back. Each light's value at a shared point is taken from the ranks
  /// whose cells the ray towards the light enters there (their walks integrate the extinction;
  /// the others read level 0), their mean where several do, every holder's mean where none does.
  /// `rho[k]` is light k's level-1 value per point (LightVolume::light_rho; empty: no solution
  /// yet, which adds no light) and `rgb` (3 per point) the light volume's light_rgb, the lights'
  /// sum weighted by their colours, which settle() makes again at the shared points.
  using Rho = std::vector<const std::vector<float>*>;
  std::vector<std::vector<double>> messages(const RankGroup& group, const Rho& rho) const;
  void settle(const RankGroup& group, const std::vector<std::vector<double>>& from_each, const Rho& rho,
              std::vector<float>& rgb) const;

  /// A rank this one shares points with, and those points as slots of points(), in the order
  /// both ranks list them (their coordinates').
  struct Peer {
    int rank = 0;
    std::vector<std::uint32_t> slots;
  };
  /// This rank's shared points (by id), indexed by slot.
  const std::vector<std::int32_t>& points() const { return m_points; }
  const std::vector<Peer>& peer_list() const { return m_peers; }
  /// Per slot, `width` values summed over every rank that holds the point, in rank order, so that
  /// all of them get the same sum (collective).
  std::vector<double> sum_over_holders(RankGroup& group, const std::vector<double>& by_slot, std::size_t width) const;

private:
  std::vector<std::int32_t> m_points;  ///< this rank's shared points, by id
  /// Per light and slot: whether the ray towards the light enters this rank's cells.
  std::vector<std::vector<std::uint8_t>> m_enters;
  std::vector<Peer> m_peers;  ///< by rank
  std::vector<std::array<double, 3>> m_colors;
};

}  // namespace penumbra::insitu

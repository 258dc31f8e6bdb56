// SPDX-License-Identifier: BSD-3-Clause
// insitu/src/shared_points.cpp -- finding the points ranks share, and settling their light
#include "shared_points.h"

#include <algorithm>
#include <array>
#include <map>
#include <string>

#include "penumbra/core/error.h"

namespace penumbra::insitu {
namespace {

using Coordinates = std::array<double, 3>;

// The points of the mesh's unmatched faces (a partition boundary is among them), by id.
std::vector<std::int32_t> boundary_points(const render::TetMesh& mesh) {
  std::vector<std::uint8_t> on(mesh.points.size(), 0);
  for (const render::BoundaryFace& f : mesh.boundary)
    for (int c = 0; c < 4; ++c)
      if (c != f.face) on[static_cast<std::size_t>(mesh.tets[static_cast<std::size_t>(f.tet)][c])] = 1;
  std::vector<std::int32_t> ids;
  for (std::size_t p = 0; p < on.size(); ++p)
    if (on[p]) ids.push_back(static_cast<std::int32_t>(p));
  return ids;
}

bool inside(const double* box, const Vec3d& p) {
  return p.x >= box[0] && p.y >= box[1] && p.z >= box[2] && p.x <= box[3] && p.y <= box[4] && p.z <= box[5];
}

Coordinates coordinates(const Vec3d& p) { return {p.x, p.y, p.z}; }

}  // namespace

SharedPoints::SharedPoints(RankGroup& group, const render::TetMesh& mesh, const std::vector<render::Light>& lights) {
  for (const render::Light& l : lights) m_colors.push_back(l.color);
  const std::vector<std::int32_t> candidates = boundary_points(mesh);
  // Each candidate goes to every other rank whose bounds hold it; what comes back are theirs.
  const Bounds& b = mesh.bounds;
  const std::vector<double> boxes = group.all_gather({b.lo.x, b.lo.y, b.lo.z, b.hi.x, b.hi.y, b.hi.z});
  const auto ranks = static_cast<std::size_t>(group.size());
  std::vector<std::vector<double>> to_each(ranks);
  for (std::size_t r = 0; r < ranks; ++r) {
    if (static_cast<int>(r) == group.rank()) continue;
    for (std::int32_t p : candidates) {
      const Vec3d& x = mesh.points[static_cast<std::size_t>(p)];
      if (inside(&boxes[6 * r], x)) to_each[r].insert(to_each[r].end(), {x.x, x.y, x.z});
    }
  }
  const std::vector<std::vector<double>> from_each = group.exchange(to_each);
  std::map<Coordinates, std::int32_t> mine;
  for (std::int32_t p : candidates) mine.emplace(coordinates(mesh.points[static_cast<std::size_t>(p)]), p);
  std::map<std::int32_t, std::uint32_t> slot_of;
  for (std::size_t r = 0; r < ranks; ++r) {
    std::vector<std::pair<Coordinates, std::int32_t>> common;
    for (std::size_t i = 0; i + 2 < from_each[r].size(); i += 3) {
      const auto it = mine.find({from_each[r][i], from_each[r][i + 1], from_each[r][i + 2]});
      if (it != mine.end()) common.push_back(*it);
    }
    if (common.empty()) continue;
    std::sort(common.begin(), common.end());
    Peer peer{static_cast<int>(r), {}};
    for (const auto& [x, p] : common) {
      const auto [it, added] = slot_of.emplace(p, static_cast<std::uint32_t>(slot_of.size()));
      if (added) m_points.push_back(p);
      peer.slots.push_back(it->second);
    }
    m_peers.push_back(std::move(peer));
  }
  for (const render::Light& l : lights) m_enters.push_back(render::rays_enter_mesh(mesh, m_points, l));
}

namespace {

// Light k's value at point p (0 before its first solution).
double value_at(const SharedPoints::Rho& rho, std::size_t k, std::int32_t p) {
  const std::vector<float>& v = *rho[k];
  return v.empty() ? 0.0 : static_cast<double>(v[static_cast<std::size_t>(p)]);
}

}  // namespace

std::vector<std::vector<double>> SharedPoints::messages(const RankGroup& group, const Rho& rho) const {
  const std::size_t lights = m_colors.size();
  require(rho.size() == lights, "SharedPoints: " + std::to_string(rho.size()) + " lights' values for " +
                                    std::to_string(lights) + " lights");
  // Per peer, per shared point in the pair's order: (enters, value) per light.
  std::vector<std::vector<double>> to_each(static_cast<std::size_t>(group.size()));
  for (const Peer& peer : m_peers) {
    std::vector<double>& out = to_each[static_cast<std::size_t>(peer.rank)];
    for (std::uint32_t s : peer.slots)
      for (std::size_t k = 0; k < lights; ++k) out.insert(out.end(), {double(m_enters[k][s]), value_at(rho, k, m_points[s])});
  }
  return to_each;
}

void SharedPoints::settle(const RankGroup& group, const std::vector<std::vector<double>>& from_each, const Rho& rho,
                          std::vector<float>& rgb) const {
  const std::size_t lights = m_colors.size(), n = m_points.size();
  // Candidates are taken rank by rank (this one in its place), so that every rank holding a point
  // sums the same values in the same order.
  std::vector<double> best(n * lights, -1), sum(n * lights, 0), count(n * lights, 0);
  auto take = [&](std::size_t s, std::size_t k, double enters, double value) {
    const std::size_t i = s * lights + k;
    if (enters > best[i]) {
      best[i] = enters;
      sum[i] = count[i] = 0;
    }
    if (enters == best[i]) {
      sum[i] += value;
      count[i] += 1;
    }
  };
  std::size_t next_peer = 0;
  for (int r = 0; r < group.size(); ++r) {
    if (r == group.rank()) {
      for (std::size_t s = 0; s < n; ++s)
        for (std::size_t k = 0; k < lights; ++k) take(s, k, m_enters[k][s], value_at(rho, k, m_points[s]));
      continue;
    }
    if (next_peer == m_peers.size() || m_peers[next_peer].rank != r) continue;
    const Peer& peer = m_peers[next_peer++];
    const std::vector<double>& got = from_each[static_cast<std::size_t>(r)];
    require(got.size() == peer.slots.size() * lights * 2,
            "SharedPoints: rank " + std::to_string(r) + " sent " + std::to_string(got.size()) + " values; expected " +
                std::to_string(peer.slots.size() * lights * 2));
    for (std::size_t j = 0; j < peer.slots.size(); ++j)
      for (std::size_t k = 0; k < lights; ++k)
        take(peer.slots[j], k, got[2 * (j * lights + k)], got[2 * (j * lights + k) + 1]);
  }
  // The sum as the light volume forms it (light_combination.cpp), from the settled values.
  for (std::size_t s = 0; s < n; ++s) {
    const auto p = static_cast<std::size_t>(m_points[s]);
    for (int c = 0; c < 3; ++c) {
      float v = 0.0f;
      for (std::size_t k = 0; k < lights; ++k) {
        const float settled = static_cast<float>(sum[s * lights + k] / count[s * lights + k]);
        v += static_cast<float>(settled * m_colors[k][static_cast<std::size_t>(c)]);
      }
      rgb[3 * p + static_cast<std::size_t>(c)] = v;
    }
  }
}

std::vector<double> SharedPoints::sum_over_holders(RankGroup& group, const std::vector<double>& by_slot,
                                                   std::size_t width) const {
  std::vector<std::vector<double>> to_each(static_cast<std::size_t>(group.size()));
  for (const Peer& peer : m_peers) {
    std::vector<double>& out = to_each[static_cast<std::size_t>(peer.rank)];
    for (std::uint32_t s : peer.slots) out.insert(out.end(), by_slot.begin() + s * width, by_slot.begin() + (s + 1) * width);
  }
  const std::vector<std::vector<double>> from_each = group.exchange(to_each);
  std::vector<double> sum(by_slot.size(), 0.0);
  std::size_t next_peer = 0;
  for (int r = 0; r < group.size(); ++r) {
    if (r == group.rank()) {
      for (std::size_t i = 0; i < sum.size(); ++i) sum[i] += by_slot[i];
      continue;
    }
    if (next_peer == m_peers.size() || m_peers[next_peer].rank != r) continue;
    const Peer& peer = m_peers[next_peer++];
    const std::vector<double>& got = from_each[static_cast<std::size_t>(r)];
    require(got.size() == peer.slots.size() * width, "SharedPoints: rank " + std::to_string(r) + " sent " +
                                                         std::to_string(got.size()) + " values; expected " +
                                                         std::to_string(peer.slots.size() * width));
    for (std::size_t j = 0; j < peer.slots.size(); ++j)
      for (std::size_t c = 0; c < width; ++c) sum[peer.slots[j] * width + c] += got[j * width + c];
  }
  return sum;
}

}  // namespace penumbra::insitu

// SPDX-License-Identifier: BSD-3-Clause
// render/src/cell_split.cpp
#include "cell_split.h"

#include <span>

namespace penumbra::render::detail {
namespace {

// Faces of the VTK cells as local vertex loops (triangles have a -1 fourth entry).
constexpr std::array<std::array<int, 4>, 6> kHexFaces{{{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4},
                                                       {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}}};
constexpr std::array<std::array<int, 4>, 5> kWedgeFaces{{{0, 1, 2, -1}, {3, 5, 4, -1}, {0, 3, 4, 1},
                                                         {1, 4, 5, 2}, {2, 5, 3, 0}}};
constexpr std::array<std::array<int, 4>, 5> kPyramidFaces{{{0, 3, 2, 1}, {0, 1, 4, -1}, {1, 2, 4, -1},
                                                           {2, 3, 4, -1}, {3, 0, 4, -1}}};

void cone(std::span<const std::array<int, 4>> faces, int n, const std::int64_t* key,
          std::vector<std::array<std::uint8_t, 4>>& out) {
  int apex = 0;
  for (int k = 1; k < n; ++k)
    if (key[k] < key[apex]) apex = k;
  auto emit = [&](int a, int b, int c) {
    if (key[a] == key[b] || key[b] == key[c] || key[a] == key[c] || key[apex] == key[a] || key[apex] == key[b] ||
        key[apex] == key[c])
      return;
    out.push_back({static_cast<std::uint8_t>(apex), static_cast<std::uint8_t>(a), static_cast<std::uint8_t>(b),
                   static_cast<std::uint8_t>(c)});
  };
  for (const auto& f : faces) {
    const int m = f[3] < 0 ? 3 : 4;
    bool has_apex = false;
    for (int k = 0; k < m; ++k) has_apex |= f[k] == apex;
    if (has_apex) continue;  // its triangulation is implied: the diagonal through the apex
    if (m == 3) {
      emit(f[0], f[1], f[2]);
      continue;
    }
    int low = 0;
    for (int k = 1; k < 4; ++k)
      if (key[f[k]] < key[f[low]]) low = k;
    if (low % 2 == 0) {  // diagonal f0-f2
      emit(f[0], f[1], f[2]);
      emit(f[0], f[2], f[3]);
    } else {  // diagonal f1-f3
      emit(f[1], f[2], f[3]);
      emit(f[1], f[3], f[0]);
    }
  }
}

}  // namespace

void split_cell(std::uint8_t vtk_type, const std::int64_t* key, std::vector<std::array<std::uint8_t, 4>>& out) {
  switch (vtk_type) {
    case 10:
      if (key[0] != key[1] && key[0] != key[2] && key[0] != key[3] && key[1] != key[2] && key[1] != key[3] &&
          key[2] != key[3])
        out.push_back({0, 1, 2, 3});
      break;
    case 12: cone(kHexFaces, 8, key, out); break;
    case 13: cone(kWedgeFaces, 6, key, out); break;
    case 14: cone(kPyramidFaces, 5, key, out); break;
    default: break;
  }
}

}  // namespace penumbra::render::detail

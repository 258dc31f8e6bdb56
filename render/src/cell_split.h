// SPDX-License-Identifier: BSD-3-Clause
// render/src/cell_split.h -- conforming split of VTK volume cells into tets
#pragma once
#include <array>
#include <cstdint>
#include <vector>

namespace penumbra::render::detail {

/// Splits one VTK cell (type 10, 12, 13 or 14) with point ids `ids` into tets, appended to
/// `out` as indices into `ids` (local 0..n-1). `key[k]` is the global rank used for the
/// diagonal rule (the welded point id): every quad face takes the diagonal through its
/// smallest key, and the cell is coned from its smallest-key vertex over the faces that do
/// not contain it. Neighbouring cells therefore agree on every shared quad face and no
/// Steiner point is needed (valid for convex cells: hex -> 6 tets, wedge -> 3, pyramid -> 2).
/// Tets with a repeated key (collapsed cells) are left out.
void split_cell(std::uint8_t vtk_type, const std::int64_t* key, std::vector<std::array<std::uint8_t, 4>>& out);

}  // namespace penumbra::render::detail

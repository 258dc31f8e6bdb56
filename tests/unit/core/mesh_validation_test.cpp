// SPDX-License-Identifier: BSD-3-Clause
// tests/unit/core/mesh_validation_test.cpp
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "fixtures/meshes.h"
#include "penumbra/core/error.h"
#include "penumbra/core/mesh_validation.h"

using namespace penumbra;
using fixtures::BlockCells;

namespace {
std::string validation_error(const MeshView& v) {
  try {
    validate_mesh(v, "test");
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::invalid_argument);
    return e.what();
  }
  return "";
}
}  // namespace

TEST(MeshValidation, AcceptsEveryBlockKind) {
  for (auto kind : {BlockCells::tets, BlockCells::hexes, BlockCells::wedges, BlockCells::pyramids}) {
    const auto m = fixtures::block(kind, 2, 2, 2, {0, 0, 0}, {1, 1, 1});
    EXPECT_EQ(validation_error(m.view()), "") << int(kind);
  }
}

TEST(MeshValidation, NamesOutOfRangeIndex) {
  auto m = fixtures::block(BlockCells::tets, 2, 2, 2, {0, 0, 0}, {1, 1, 1});
  m.connectivity[4 * 7 + 2] = 9999;
  const std::string msg = validation_error(m.view());
  EXPECT_NE(msg.find("cell 7"), std::string::npos) << msg;
  EXPECT_NE(msg.find("9999"), std::string::npos) << msg;
  m.connectivity[4 * 7 + 2] = -1;
  EXPECT_NE(validation_error(m.view()).find("cell 7"), std::string::npos);
}

TEST(MeshValidation, NamesNonFiniteCoordinate) {
  auto m = fixtures::block(BlockCells::hexes, 2, 2, 2, {0, 0, 0}, {1, 1, 1});
  m.xyz[3 * 5 + 1] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_NE(validation_error(m.view()).find("point 5"), std::string::npos);
  m.xyz[3 * 5 + 1] = std::numeric_limits<double>::infinity();
  EXPECT_NE(validation_error(m.view()).find("point 5"), std::string::npos);
}

TEST(MeshValidation, ExtentAndPositionWithinTheLimitsAreAccepted) {
  for (double size : {1e-80, 1e-15, 1.0, 1e15, 1e80}) {
    const auto m = fixtures::block(BlockCells::hexes, 2, 2, 2, {0, 0, 0}, {size, size, size});
    EXPECT_EQ(validation_error(m.view()), "") << size;
    const double far = 1e8 * size;  // 1e8 extents away
    const auto moved = fixtures::block(BlockCells::hexes, 2, 2, 2, {far, 0, -far}, {far + size, size, size - far});
    EXPECT_EQ(validation_error(moved.view()), "") << size;
  }
}

TEST(MeshValidation, ExtentBeyondTheLimitsIsRefusedWithTheLimitAndTheRemedy) {
  for (double size : {1e-100, 1e100, 1e300}) {
    const auto m = fixtures::block(BlockCells::hexes, 2, 2, 2, {0, 0, 0}, {size, size, size});
    const std::string msg = validation_error(m.view());
    EXPECT_NE(msg.find("the mesh's extent (bounding-box diagonal) is"), std::string::npos) << msg;
    EXPECT_NE(msg.find("1e-90 to 1e+90"), std::string::npos) << msg;
    EXPECT_NE(msg.find("another unit"), std::string::npos) << msg;
  }
  // The largest doubles: an extent beyond double's range is refused too.
  const double big = std::numeric_limits<double>::max();
  fixtures::OwnedMesh huge;
  huge.add_cell(10, {huge.add_point(-big, 0, 0), huge.add_point(big, 0, 0), huge.add_point(0, big, 0),
                     huge.add_point(0, 0, big)});
  EXPECT_NE(validation_error(huge.view()).find("extent (bounding-box diagonal) is inf"), std::string::npos)
      << validation_error(huge.view());
}

TEST(MeshValidation, MeshTooFarFromTheOriginIsRefused) {
  const auto m = fixtures::block(BlockCells::tets, 2, 2, 2, {3e10, 0, 0}, {3e10 + 1, 1, 1});
  const std::string msg = validation_error(m.view());
  EXPECT_NE(msg.find("extents from the origin"), std::string::npos) << msg;
  EXPECT_NE(msg.find("at most 1e+09"), std::string::npos) << msg;
}

TEST(MeshValidation, NamesZeroVolumeCell) {
  fixtures::OwnedMesh m;
  for (double x : {0.0, 1.0})
    for (double y : {0.0, 1.0}) m.add_point(x, y, 0);  // four coplanar points
  m.add_point(0, 0, 1);
  m.add_cell(10, {0, 1, 2, 4});
  m.add_cell(10, {0, 1, 2, 3});
  const std::string msg = validation_error(m.view());
  EXPECT_NE(msg.find("cell 1"), std::string::npos) << msg;
  EXPECT_NE(msg.find("zero volume"), std::string::npos) << msg;
}

TEST(MeshValidation, RejectsSizeMismatchAndUnknownType) {
  auto m = fixtures::block(BlockCells::tets, 1, 1, 1, {0, 0, 0}, {1, 1, 1});
  auto v = m.view();
  v.cell_type_count = 3;  // neither 1 nor the cell count
  EXPECT_NE(validation_error(v).find("cell types"), std::string::npos);
  m.types[2] = 7;  // VTK polygon: not a volume cell
  EXPECT_NE(validation_error(m.view()).find("cell 2"), std::string::npos);
  auto v2 = m.view();
  v2.connectivity.count = 0;
  EXPECT_NE(validation_error(v2), "");
}

TEST(MeshValidation, InvertedTetIsNotAnError) {
  auto m = fixtures::block(BlockCells::tets, 1, 1, 1, {0, 0, 0}, {1, 1, 1});
  std::swap(m.connectivity[0], m.connectivity[1]);
  EXPECT_EQ(validation_error(m.view()), "");
}

TEST(MeshValidation, UniformCellTypeWithoutOffsets) {
  auto m = fixtures::block(BlockCells::hexes, 2, 1, 1, {0, 0, 0}, {1, 1, 1});
  auto v = m.view();
  v.offsets = {};
  v.cell_type_count = 1;
  EXPECT_EQ(v.cell_count(), 2u);
  EXPECT_EQ(validation_error(v), "");
  v.connectivity.count = 11;  // not a multiple of 8
  EXPECT_NE(validation_error(v).find("multiple of 8"), std::string::npos);
}

// Coordinates as three arrays (x[], y[], z[], float or double, packed or strided) read as the
// interleaved ones; one array missing is named.
TEST(MeshView, ThreeCoordinateArraysReadAsInterleavedPoints) {
  const auto m = fixtures::block(BlockCells::tets, 2, 2, 2, {0, 0, 0}, {1, 2, 3});
  const MeshView interleaved = m.view();
  const std::size_t n = m.point_count();
  std::vector<double> x(n), y(n), z(n);
  std::vector<float> soa(4 * n);  // x, y, z and a spare float per point: a stride of 16 bytes
  for (std::size_t i = 0; i < n; ++i) {
    x[i] = m.xyz[3 * i], y[i] = m.xyz[3 * i + 1], z[i] = m.xyz[3 * i + 2];
    for (int a = 0; a < 3; ++a) soa[4 * i + a] = static_cast<float>(m.xyz[3 * i + a]);
  }
  MeshView packed = interleaved;
  packed.points = {nullptr, n, 0};
  const double* axes[3] = {x.data(), y.data(), z.data()};
  for (int a = 0; a < 3; ++a) packed.axes[a] = {reinterpret_cast<const std::byte*>(axes[a]), n, sizeof(double)};
  MeshView strided = packed;
  strided.point_type = ScalarType::float32;
  for (int a = 0; a < 3; ++a) strided.axes[a] = {reinterpret_cast<const std::byte*>(soa.data() + a), n, 4 * sizeof(float)};
  for (std::size_t i = 0; i < n; ++i) {
    EXPECT_EQ(packed.point(i), interleaved.point(i)) << i;
    EXPECT_EQ(strided.point(i), interleaved.point(i)) << i;  // the block's coordinates are exact in float
  }
  EXPECT_NO_THROW(validate_mesh(packed, "test"));
  packed.axes[1].data = nullptr;
  try {
    validate_mesh(packed, "test");
    ADD_FAILURE() << "expected the missing array to be named";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("coordinate array y is null"), std::string::npos) << e.what();
  }
}

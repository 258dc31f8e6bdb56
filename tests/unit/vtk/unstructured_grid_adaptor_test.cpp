// SPDX-License-Identifier: BSD-3-Clause
// tests/unit/vtk/unstructured_grid_adaptor_test.cpp -- zero-copy views and the copy paths
#include <gtest/gtest.h>
#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkDoubleArray.h>
#include <vtkFloatArray.h>
#include <vtkIntArray.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkSOADataArrayTemplate.h>
#include <vtkTypeInt32Array.h>
#include <vtkTypeInt64Array.h>
#include <vtkUnsignedCharArray.h>

#include "penumbra/core/error.h"
#include "penumbra/core/mesh_validation.h"
#include "penumbra/vtk/unstructured_grid_adaptor.h"
#include "vtk_test_util.h"

namespace penumbra {
namespace {

using vtk::UnstructuredGridAdaptor;

fixtures::OwnedMesh small_block(fixtures::BlockCells cells = fixtures::BlockCells::tets) {
  return fixtures::block(cells, 2, 2, 2, {0, 0, 0}, {1, 1, 1});
}

void add_point_field(vtkUnstructuredGrid* g, const char* name) {
  vtkNew<vtkDoubleArray> a;
  a->SetName(name);
  for (vtkIdType i = 0; i < g->GetNumberOfPoints(); ++i) a->InsertNextValue(0.5 * static_cast<double>(i));
  g->GetPointData()->AddArray(a);
}

void add_cell_field(vtkUnstructuredGrid* g, const char* name) {
  vtkNew<vtkFloatArray> a;
  a->SetName(name);
  a->SetNumberOfComponents(3);
  for (vtkIdType i = 0; i < g->GetNumberOfCells(); ++i) a->InsertNextTuple3(i, 2.0 * i, 3.0 * i);
  g->GetCellData()->AddArray(a);
}

TEST(VtkAdaptor, Int64GridIsViewedWithoutCopies) {
  auto g = test::to_vtk(small_block(), true, VTK_DOUBLE);
  add_point_field(g, "p");
  add_cell_field(g, "v");
  ASSERT_TRUE(g->GetCells()->IsStorage64Bit());
  UnstructuredGridAdaptor a(g, 7);
  const pnb_mesh_desc& m = a.mesh();
  EXPECT_TRUE(a.mesh_is_zero_copy());
  EXPECT_EQ(m.points, g->GetPoints()->GetData()->GetVoidPointer(0));
  EXPECT_EQ(m.point_type, PNB_FLOAT64);
  EXPECT_EQ(m.index_type, PNB_INT64);
  EXPECT_EQ(m.connectivity, g->GetCells()->GetConnectivityArray64()->GetPointer(0));
  EXPECT_EQ(m.offsets, g->GetCells()->GetOffsetsArray64()->GetPointer(0));
  EXPECT_EQ(m.cell_types, g->GetCellTypesArray()->GetPointer(0));
  EXPECT_EQ(m.cell_types_count, g->GetNumberOfCells());
  EXPECT_EQ(m.point_count, g->GetNumberOfPoints());
  EXPECT_EQ(m.topology_version, 7u);

  ASSERT_EQ(a.fields().size(), 2u);
  const pnb_field_desc* p = a.find_field("p", PNB_POINT_FIELD);
  ASSERT_NE(p, nullptr);
  EXPECT_EQ(p->values, g->GetPointData()->GetArray("p")->GetVoidPointer(0));
  EXPECT_EQ(p->type, PNB_FLOAT64);
  const pnb_field_desc* v = a.find_field("v", PNB_CELL_FIELD);
  ASSERT_NE(v, nullptr);
  EXPECT_EQ(v->values, g->GetCellData()->GetArray("v")->GetVoidPointer(0));
  EXPECT_EQ(v->components, 3);
  EXPECT_EQ(v->type, PNB_FLOAT32);
  EXPECT_EQ(v->count, g->GetNumberOfCells());
  EXPECT_EQ(a.find_field("v", PNB_POINT_FIELD), nullptr);
  EXPECT_TRUE(a.report().copied_fields.empty());
  EXPECT_NO_THROW(validate_mesh(a.mesh_view(), "test"));
}

TEST(VtkAdaptor, Int32GridAndFloatPointsAreViewedWithoutCopies) {
  auto g = test::to_vtk(small_block(fixtures::BlockCells::hexes), false, VTK_FLOAT);
  ASSERT_FALSE(g->GetCells()->IsStorage64Bit());
  UnstructuredGridAdaptor a(g);
  const pnb_mesh_desc& m = a.mesh();
  EXPECT_TRUE(a.mesh_is_zero_copy());
  EXPECT_EQ(m.index_type, PNB_INT32);
  EXPECT_EQ(m.point_type, PNB_FLOAT32);
  EXPECT_EQ(m.points, g->GetPoints()->GetData()->GetVoidPointer(0));
  EXPECT_EQ(m.connectivity, g->GetCells()->GetConnectivityArray32()->GetPointer(0));
  EXPECT_EQ(m.offsets, g->GetCells()->GetOffsetsArray32()->GetPointer(0));
  EXPECT_EQ(m.connectivity_count, 8 * g->GetNumberOfCells());
  EXPECT_NO_THROW(validate_mesh(a.mesh_view(), "test"));
}

TEST(VtkAdaptor, EveryVolumeCellTypeIsViewed) {
  for (auto cells : {fixtures::BlockCells::tets, fixtures::BlockCells::hexes, fixtures::BlockCells::wedges,
                     fixtures::BlockCells::pyramids}) {
    auto g = test::to_vtk(small_block(cells));
    UnstructuredGridAdaptor a(g);
    EXPECT_TRUE(a.mesh_is_zero_copy());
    EXPECT_EQ(a.report().volume_cells, static_cast<std::size_t>(g->GetNumberOfCells()));
    EXPECT_NO_THROW(validate_mesh(a.mesh_view(), "test"));
  }
}

TEST(VtkAdaptor, SurfaceCellsAreFilteredOutWithTheirCellValues) {
  auto mesh = small_block();
  const std::size_t tets = mesh.cell_count();
  // A boundary triangle after every tet: the typical "volume + boundary faces" file.
  fixtures::OwnedMesh mixed;
  mixed.xyz = mesh.xyz;
  for (std::size_t c = 0; c < tets; ++c) {
    const auto* ids = &mesh.connectivity[static_cast<std::size_t>(mesh.offsets[c])];
    mixed.add_cell(VTK_TETRA, {ids[0], ids[1], ids[2], ids[3]});
    mixed.add_cell(VTK_TRIANGLE, {ids[0], ids[1], ids[2]});
  }
  auto g = test::to_vtk(mixed, false);
  add_point_field(g, "p");
  vtkNew<vtkDoubleArray> cell_index;
  cell_index->SetName("index");
  for (vtkIdType i = 0; i < g->GetNumberOfCells(); ++i) cell_index->InsertNextValue(static_cast<double>(i));
  g->GetCellData()->AddArray(cell_index);

  UnstructuredGridAdaptor a(g);
  EXPECT_FALSE(a.mesh_is_zero_copy());
  EXPECT_TRUE(a.report().cells_copied);
  EXPECT_FALSE(a.report().points_copied);
  EXPECT_EQ(a.report().dropped_surface_cells, tets);
  EXPECT_EQ(a.mesh().cell_types_count, static_cast<std::int64_t>(tets));
  EXPECT_EQ(a.mesh().points, g->GetPoints()->GetData()->GetVoidPointer(0));  // points stay a view
  const pnb_field_desc* p = a.find_field("p", PNB_POINT_FIELD);
  ASSERT_NE(p, nullptr);
  EXPECT_EQ(p->values, g->GetPointData()->GetArray("p")->GetVoidPointer(0));
  const pnb_field_desc* idx = a.find_field("index", PNB_CELL_FIELD);
  ASSERT_NE(idx, nullptr);
  ASSERT_EQ(idx->count, static_cast<std::int64_t>(tets));
  const auto* values = static_cast<const double*>(idx->values);
  for (std::size_t c = 0; c < tets; ++c) EXPECT_EQ(values[c], 2.0 * static_cast<double>(c)) << "cell " << c;
  EXPECT_NO_THROW(validate_mesh(a.mesh_view(), "test"));
  EXPECT_NE(a.report().summary().find("surface"), std::string::npos) << a.report().summary();
}

TEST(VtkAdaptor, VoxelsAndQuadraticCellsBecomeLinearCells) {
  fixtures::OwnedMesh m;
  // Unit voxel, x-fastest point order, then a quadratic tet reusing 4 corners + 6 mid-edge points.
  for (int k = 0; k < 2; ++k)
    for (int j = 0; j < 2; ++j)
      for (int i = 0; i < 2; ++i) m.add_point(i, j, k);
  m.add_cell(VTK_VOXEL, {0, 1, 2, 3, 4, 5, 6, 7});
  for (int e = 0; e < 6; ++e) m.add_point(2 + 0.1 * e, 0, 0);
  m.add_cell(VTK_QUADRATIC_TETRA, {1, 3, 2, 5, 8, 9, 10, 11, 12, 13});
  auto g = test::to_vtk(m);
  UnstructuredGridAdaptor a(g);
  EXPECT_EQ(a.report().linearized_cells, 2u);
  ASSERT_EQ(a.mesh().cell_types_count, 2);
  EXPECT_EQ(a.mesh().cell_types[0], PNB_HEXAHEDRON);
  EXPECT_EQ(a.mesh().cell_types[1], PNB_TETRA);
  const auto* conn = static_cast<const std::int64_t*>(a.mesh().connectivity);
  const std::int64_t hex[8] = {0, 1, 3, 2, 4, 5, 7, 6};  // VTK hexahedron order: around each face
  for (int k = 0; k < 8; ++k) EXPECT_EQ(conn[k], hex[k]) << "hex point " << k;
  const std::int64_t tet[4] = {1, 3, 2, 5};
  for (int k = 0; k < 4; ++k) EXPECT_EQ(conn[8 + k], tet[k]) << "tet point " << k;
}

TEST(VtkAdaptor, SurfaceOnlyGridIsAClearError) {
  fixtures::OwnedMesh m;
  for (int i = 0; i < 4; ++i) m.add_point(i & 1, i >> 1, 0);
  m.add_cell(VTK_TRIANGLE, {0, 1, 2});
  m.add_cell(VTK_QUAD, {0, 1, 3, 2});
  auto g = test::to_vtk(m);
  try {
    UnstructuredGridAdaptor a(g);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::invalid_argument);
    const std::string msg = e.what();
    EXPECT_NE(msg.find("no volume cells"), std::string::npos) << msg;
    EXPECT_NE(msg.find("1 Triangle (5)"), std::string::npos) << msg;
    EXPECT_NE(msg.find("1 Quad (9)"), std::string::npos) << msg;
  }
}

TEST(VtkAdaptor, NullOrEmptyGridIsAnError) {
  EXPECT_THROW(UnstructuredGridAdaptor(nullptr), Error);
  vtkNew<vtkUnstructuredGrid> empty;
  EXPECT_THROW(UnstructuredGridAdaptor a(empty), Error);
  auto no_cells = test::to_vtk(small_block());
  no_cells->SetCells(VTK_TETRA, vtkNew<vtkCellArray>());
  EXPECT_THROW(UnstructuredGridAdaptor a(no_cells), Error);
}

TEST(VtkAdaptor, NonFloatAndNonContiguousArraysAreConvertedToFloat64) {
  // Integer coordinates (a block over [0,2]^3 with unit cubes): must be converted to float64.
  auto g = test::to_vtk(fixtures::block(fixtures::BlockCells::tets, 2, 2, 2, {0, 0, 0}, {2, 2, 2}), true, VTK_INT);
  vtkNew<vtkIntArray> material;
  material->SetName("material");
  for (vtkIdType i = 0; i < g->GetNumberOfCells(); ++i) material->InsertNextValue(static_cast<int>(i % 3));
  g->GetCellData()->AddArray(material);
  vtkNew<vtkSOADataArrayTemplate<double>> soa;  // struct-of-arrays: not one packed block
  soa->SetName("velocity");
  soa->SetNumberOfComponents(3);
  soa->SetNumberOfTuples(g->GetNumberOfPoints());
  for (vtkIdType i = 0; i < g->GetNumberOfPoints(); ++i) soa->SetTuple3(i, i, -i, 0.5 * i);
  g->GetPointData()->AddArray(soa);

  UnstructuredGridAdaptor a(g);
  EXPECT_TRUE(a.report().points_copied);
  EXPECT_EQ(a.mesh().point_type, PNB_FLOAT64);
  const auto* xyz = static_cast<const double*>(a.mesh().points);
  for (vtkIdType i = 0; i < g->GetNumberOfPoints(); ++i)
    for (int c = 0; c < 3; ++c) ASSERT_EQ(xyz[3 * i + c], g->GetPoint(i)[c]);
  const pnb_field_desc* m = a.find_field("material", PNB_CELL_FIELD);
  ASSERT_NE(m, nullptr);
  EXPECT_EQ(m->type, PNB_FLOAT64);
  EXPECT_EQ(static_cast<const double*>(m->values)[4], 1.0);
  const pnb_field_desc* v = a.find_field("velocity", PNB_POINT_FIELD);
  ASSERT_NE(v, nullptr);
  EXPECT_EQ(v->components, 3);
  EXPECT_EQ(static_cast<const double*>(v->values)[3 * 5 + 1], -5.0);
  EXPECT_EQ(a.report().copied_fields.size(), 2u);
  EXPECT_NO_THROW(validate_mesh(a.mesh_view(), "test"));
}

TEST(VtkAdaptor, CopyFilterSkipsOnlyFieldsThatNeedACopy) {
  auto g = test::to_vtk(small_block());
  add_point_field(g, "p");  // float64: a view, exposed whatever the filter says
  for (const char* name : {"ids", "material"}) {
    vtkNew<vtkIntArray> a;
    a->SetName(name);
    for (vtkIdType i = 0; i < g->GetNumberOfCells(); ++i) a->InsertNextValue(static_cast<int>(i));
    g->GetCellData()->AddArray(a);
  }
  UnstructuredGridAdaptor a(g, 1, [](std::string_view name) { return name == "material"; });
  EXPECT_NE(a.find_field("p", PNB_POINT_FIELD), nullptr);
  EXPECT_NE(a.find_field("material", PNB_CELL_FIELD), nullptr);
  EXPECT_EQ(a.find_field("ids", PNB_CELL_FIELD), nullptr);
  ASSERT_EQ(a.report().unconverted_fields.size(), 1u);
  EXPECT_EQ(a.report().unconverted_fields[0], "ids");
}

TEST(VtkAdaptor, DescriptorsSurviveAMove) {
  auto g = test::to_vtk(small_block(), true);
  add_point_field(g, "p");
  UnstructuredGridAdaptor a(g);
  const void* points = a.mesh().points;
  const void* values = a.fields()[0].values;
  UnstructuredGridAdaptor b(std::move(a));
  EXPECT_EQ(b.mesh().points, points);
  EXPECT_EQ(b.fields()[0].values, values);
  EXPECT_STREQ(b.fields()[0].name, "p");
}

}  // namespace
}  // namespace penumbra

// SPDX-License-Identifier: BSD-3-Clause
// tests/unit/vtk/input_series_test.cpp -- every shared data file through the readers and adaptor
#include <gtest/gtest.h>
#include <vtkPointData.h>

#include <cmath>
#include <fstream>
#include <map>

#include "input_series.h"
#include "netcdf_size.h"
#include "penumbra/core/error.h"
#include "penumbra/core/mesh_validation.h"
#include "penumbra/vtk/unstructured_grid_adaptor.h"
#include "vtk_test_util.h"

namespace penumbra {
namespace {

namespace fs = std::filesystem;
using replay::InputSeries;
using vtk::UnstructuredGridAdaptor;

struct Expected {
  std::size_t steps, cells, points;
  const char* field;  // one field the file must yield
};

// Counts from tests/data/README.md (mug.e: 3954 block points minus 180 shared nodes).
const std::map<std::string, Expected> k_expected = {
    {"mug.e", {21, 2476, 3774, "diffused"}},
    {"disk_out_ref.ex2", {1, 7472, 8499, "Temp"}},
    {"can.vtu", {1, 4800, 6724, "EQPS"}},
    {"post.vtk", {1, 8750, 2288, "Pressure"}},
    // README counts 1400 points per block; the 3 blocks share 400 nodes (1000 unique ids and
    // 1000 unique coordinates), so the merged mesh has 1000.
    {"mesh_fs8.exo", {1, 1344, 1000, "ObjectId"}},
    {"mfem_ex16_holeblock10k.vtk.series", {11, 9910, 3216, "temperature"}},
};

std::vector<fs::path> all_inputs() {
  std::vector<fs::path> files;
  for (const auto& e : fs::recursive_directory_iterator(test::data_dir())) {
    const std::string ext = e.path().extension().string();
    if (e.is_regular_file() && ext != ".md" && ext != ".sha256") files.push_back(e.path());
  }
  return files;
}

TEST(VtkInputs, EveryBundledDataFileGivesAValidMeshOrAClearError) {
  const auto files = all_inputs();
  ASSERT_GE(files.size(), 7u) << "test data missing under " << test::data_dir();
  std::size_t checked = 0;
  for (const auto& path : files) {
    SCOPED_TRACE(path.string());
    auto series = InputSeries::open(path.string());
    ASSERT_GE(series->size(), 1u);
    replay::Step step = series->load(0);
    ASSERT_TRUE(step.grid);
    if (path.filename() == "blow.vtk") {  // a shell of triangles and quads: nothing to volume-render
      try {
        UnstructuredGridAdaptor a(step.grid);
        ADD_FAILURE() << "blow.vtk should be rejected";
      } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("no volume cells"), std::string::npos) << e.what();
      }
      ++checked;
      continue;
    }
    UnstructuredGridAdaptor a(step.grid);
    EXPECT_NO_THROW(validate_mesh(a.mesh_view(), "test")) << a.report().summary();
    EXPECT_GT(a.mesh().cell_types_count, 0);
    const auto it = k_expected.find(path.filename().string());
    if (it != k_expected.end()) {
      EXPECT_EQ(series->size(), it->second.steps);
      EXPECT_EQ(static_cast<std::size_t>(a.mesh().cell_types_count), it->second.cells);
      EXPECT_EQ(static_cast<std::size_t>(a.mesh().point_count), it->second.points);
      const char* f = it->second.field;
      EXPECT_TRUE(a.find_field(f, PNB_POINT_FIELD) || a.find_field(f, PNB_CELL_FIELD)) << f;
      EXPECT_TRUE(a.mesh_is_zero_copy()) << a.report().summary();
    }
    ++checked;
  }
  EXPECT_EQ(checked, files.size());
}

TEST(VtkInputs, MugBlocksShareNodesAndTimesAreRead) {
  auto series = InputSeries::open((test::data_dir() / "mug.e").string());
  ASSERT_EQ(series->size(), 21u);
  const replay::Step last = series->load(20);
  EXPECT_NEAR(last.time, 2.0, 1e-12);  // Exodus stores the times as doubles: only rounding differs
  EXPECT_EQ(last.cycle, 20);
  // Merged by GlobalNodeId: every node id appears once (a duplicate would be a false boundary).
  vtkDataArray* ids = last.grid->GetPointData()->GetArray("GlobalNodeId");
  ASSERT_NE(ids, nullptr);
  std::set<long long> unique;
  for (vtkIdType i = 0; i < ids->GetNumberOfTuples(); ++i) unique.insert(static_cast<long long>(ids->GetComponent(i, 0)));
  EXPECT_EQ(unique.size(), static_cast<std::size_t>(last.grid->GetNumberOfPoints()));
  EXPECT_EQ(last.grid->GetNumberOfPoints(), 3774);
  // The fields change over time while the geometry stays.
  const replay::Step first = series->load(0);
  UnstructuredGridAdaptor a0(first.grid), a20(last.grid);
  const auto* f0 = a0.find_field("diffused", PNB_POINT_FIELD);
  const auto* f20 = a20.find_field("diffused", PNB_POINT_FIELD);
  ASSERT_TRUE(f0 && f20);
  EXPECT_NE(f0->values, f20->values);
}

TEST(VtkInputs, SeriesTimeAndCycleComeFromTheData) {
  auto series = InputSeries::open(
      (test::data_dir() / "generated/mfem_ex16_holeblock10k/mfem_ex16_holeblock10k.vtk.series").string());
  ASSERT_EQ(series->size(), 11u);
  const replay::Step s = series->load(3);
  EXPECT_EQ(s.cycle, 30);  // CYCLE field data, not the step index
  EXPECT_NEAR(s.time, 0.6, 1e-9);
}

TEST(VtkInputs, PvdCollectionIsRead) {
  test::TempDir dir("pvd");
  const auto can = (test::data_dir() / "can.vtu").string();
  std::ofstream(dir.path() / "run.pvd") << "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n"
                                        << "<Collection>\n<DataSet timestep=\"0.5\" part=\"0\" file=\"" << can << "\"/>\n"
                                        << "<DataSet timestep=\"1.5\" part=\"0\" file=\"" << can << "\"/>\n"
                                        << "</Collection>\n</VTKFile>\n";
  auto series = InputSeries::open((dir.path() / "run.pvd").string());
  ASSERT_EQ(series->size(), 2u);
  const replay::Step s = series->load(1);
  EXPECT_EQ(s.time, 1.5);
  EXPECT_EQ(s.grid->GetNumberOfCells(), 4800);
}

/// Expects open()+load(0) to throw a penumbra::Error whose message contains `needle`.
void expect_read_error(const fs::path& path, const std::string& needle) {
  SCOPED_TRACE(path.string());
  try {
    auto series = InputSeries::open(path.string());
    for (std::size_t i = 0; i < series->size(); ++i) series->load(i);
    ADD_FAILURE() << "no error for " << path;
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
  }
}

void copy_prefix(const fs::path& from, const fs::path& to, std::size_t bytes) {
  std::ifstream in(from, std::ios::binary);
  std::string data(bytes, '\0');
  in.read(data.data(), static_cast<std::streamsize>(bytes));
  std::ofstream(to, std::ios::binary).write(data.data(), in.gcount());
}

TEST(VtkInputs, MissingAndCorruptFilesAreClearErrors) {
  test::TempDir dir("bad");
  const fs::path d = dir.path();
  expect_read_error(d / "nope.vtu", "does not exist");
  std::ofstream(d / "x.txt") << "hello";
  expect_read_error(d / "x.txt", "unsupported extension");
  std::ofstream(d / "garbage.vtu") << "this is not xml";
  expect_read_error(d / "garbage.vtu", "cannot read");
  std::ofstream(d / "garbage.vtk") << "# vtk DataFile Version 3.0\nx\nASCII\nDATASET POLYDATA\n";
  expect_read_error(d / "garbage.vtk", "UNSTRUCTURED_GRID");
  std::ofstream(d / "garbage.e") << "CDF not really";
  expect_read_error(d / "garbage.e", "cannot read");
  copy_prefix(test::data_dir() / "post.vtk", d / "truncated.vtk", 40000);
  expect_read_error(d / "truncated.vtk", "cannot read");
  copy_prefix(test::data_dir() / "can.vtu", d / "truncated.vtu", 300000);
  expect_read_error(d / "truncated.vtu", "cannot read");
  // Cut inside the element blocks, and inside the time-step records (which netCDF itself would
  // read back as zeros without complaint).
  copy_prefix(test::data_dir() / "mug.e", d / "truncated.e", 20000);
  expect_read_error(d / "truncated.e", "truncated");
  copy_prefix(test::data_dir() / "mug.e", d / "truncated_records.e", 1900000);
  expect_read_error(d / "truncated_records.e", "truncated");
  std::ofstream(d / "bad.series") << "{\"files\": [{\"name\": \"missing.vtk\", \"time\": 0}]}";
  expect_read_error(d / "bad.series", "does not exist");
  std::ofstream(d / "broken.series") << "{\"files\": [";
  expect_read_error(d / "broken.series", "not valid JSON");
  std::ofstream(d / "bad.pvd") << "<VTKFile><Collection><DataSet file=\"gone.vtu\"/></Collection></VTKFile>";
  expect_read_error(d / "bad.pvd", "does not exist");
}

}  // namespace
}  // namespace penumbra

namespace penumbra {
namespace {

TEST(VtkInputs, NetcdfHeaderGivesTheCompleteFileSize) {
  for (const char* name : {"mug.e", "disk_out_ref.ex2", "mesh_fs8.exo"}) {
    const auto path = test::data_dir() / name;
    const auto needed = replay::netcdf_classic_min_size(path.string());
    ASSERT_TRUE(needed.has_value()) << name;
    const auto size = std::filesystem::file_size(path);
    // The variables end where the file ends, up to padding: the bound leaves out the last
    // variable's 3 padding bytes, and disk_out_ref.ex2 has 4 more bytes after its last variable.
    EXPECT_LE(*needed, size) << name;
    EXPECT_GE(*needed + 8, size) << name;
  }
  EXPECT_FALSE(replay::netcdf_classic_min_size((test::data_dir() / "can.vtu").string()).has_value());
}

}  // namespace
}  // namespace penumbra

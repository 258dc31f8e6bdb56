// SPDX-License-Identifier: BSD-3-Clause
// tests/unit/vtk/replay_test.cpp -- penumbra-replay end to end: files -> C API -> Cinema database
#include <gtest/gtest.h>
#include <vtkDoubleArray.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkXMLUnstructuredGridWriter.h>

#include <fstream>
#include <sstream>

#include "penumbra/render/image.h"
#include "replay.h"
#include "vtk_test_util.h"

namespace penumbra {
namespace {

namespace fs = std::filesystem;

struct Result {
  int rc = -1;
  std::string out, err;
};

Result replay_run(const std::vector<std::string>& args) {
  std::ostringstream out, err;
  Result r;
  r.rc = replay::run(args, out, err);
  r.out = out.str();
  r.err = err.str();
  return r;
}

/// A small config (64x64, one orbit camera) rendering `field` into `dir`.
std::string config(const fs::path& dir, const std::string& field) {
  return R"({"output":{"directory":")" + dir.string() + R"("},"image":{"width":64,"height":64},)" +
         R"("cameras":{"phi":[30],"theta":[20]},"fields":[{"name":")" + field + R"("}]})";
}

std::vector<std::string> read_lines(const fs::path& p) {
  std::ifstream in(p);
  std::vector<std::string> lines;
  for (std::string l; std::getline(in, l);)
    if (!l.empty()) lines.push_back(l);
  return lines;
}

std::size_t png_count(const fs::path& dir) {
  std::size_t n = 0;
  for (const auto& e : fs::recursive_directory_iterator(dir)) n += e.path().extension() == ".png";
  return n;
}

/// Replays `input` rendering `field` and checks the database has `rows` images.
void expect_database(const std::string& input, const std::string& field, std::size_t rows,
                     const std::vector<std::string>& extra = {}) {
  SCOPED_TRACE(input);
  test::TempDir tmp("replay");
  const fs::path db = tmp.path() / "db";
  std::vector<std::string> args{config(db, field), (test::data_dir() / input).string(), "--quiet"};
  args.insert(args.end(), extra.begin(), extra.end());
  const Result r = replay_run(args);
  ASSERT_EQ(r.rc, 0) << r.err;
  EXPECT_TRUE(r.err.empty()) << r.err;
  const auto lines = read_lines(db / "data.csv");
  ASSERT_EQ(lines.size(), rows + 1) << "header + one row per image";
  EXPECT_NE(lines[0].rfind(",FILE"), std::string::npos) << lines[0];
  EXPECT_EQ(png_count(db), rows);
}

TEST(Replay, MugExodusAllTwentyOneSteps) {
  test::TempDir tmp("mug");
  const fs::path db = tmp.path() / "db";
  const Result r = replay_run({config(db, "diffused"), (test::data_dir() / "mug.e").string()});
  ASSERT_EQ(r.rc, 0) << r.err;
  EXPECT_NE(r.out.find("21 step(s) executed, mesh published 1 time(s), 0 failure(s)"), std::string::npos) << r.out;
  const auto lines = read_lines(db / "data.csv");
  ASSERT_EQ(lines.size(), 22u);
  EXPECT_EQ(png_count(db), 21u);
  // The time column comes from the file's time values: 0, 0.1, ..., 2 (written shortest-exact).
  EXPECT_EQ(lines[1].substr(0, lines[1].find(',')), "0") << lines[1];
  const std::string last_time = lines.back().substr(0, lines.back().find(','));
  EXPECT_NEAR(std::stod(last_time), 2.0, 1e-12) << lines.back();
}

TEST(Replay, StepRangeSelectsSteps) { expect_database("mug.e", "convected", 3, {"--steps", "5:8"}); }
TEST(Replay, DiskOutRefExodus) { expect_database("disk_out_ref.ex2", "Temp", 1); }
TEST(Replay, CanVtuCellField) { expect_database("can.vtu", "EQPS", 1); }
TEST(Replay, PostLegacyVtk) { expect_database("post.vtk", "Pressure", 1); }
TEST(Replay, MfemVtkSeries) {
  expect_database("generated/mfem_ex16_holeblock10k/mfem_ex16_holeblock10k.vtk.series", "temperature", 11);
}

TEST(Replay, ProgressReportsTimeAndCycleFromTheData) {
  test::TempDir tmp("mfem");
  const Result r = replay_run({config(tmp.path() / "db", "temperature"),
                               (test::data_dir() / "generated/mfem_ex16_holeblock10k/mfem_ex16_holeblock10k.vtk.series").string(),
                               "--steps", "2:4"});
  ASSERT_EQ(r.rc, 0) << r.err;
  EXPECT_NE(r.out.find("step 2 time 0.4 cycle 20"), std::string::npos) << r.out;  // TIME/CYCLE field data
  EXPECT_NE(r.out.find("step 3 time 0.6 cycle 30"), std::string::npos) << r.out;
}

// mesh_fs8.exo has no result variables. The reader still provides each cell's element block id
// (ObjectId), so a config can render the blocks; a config naming a field the file lacks is
// refused before any database is created, listing what is available.
TEST(Replay, MeshOnlyExodusRendersBlockIdsAndRefusesMissingFields) {
  expect_database("mesh_fs8.exo", "ObjectId", 1);
  test::TempDir tmp("fs8");
  const fs::path db = tmp.path() / "db";
  const Result r = replay_run({config(db, "temperature"), (test::data_dir() / "mesh_fs8.exo").string()});
  EXPECT_EQ(r.rc, 1);
  EXPECT_NE(r.err.find("'temperature'"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("available: "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("ObjectId"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(db));
}

void write_block_vtu(const fs::path& path, int n) {
  auto grid = test::to_vtk(fixtures::block(fixtures::BlockCells::tets, n, n, n, {0, 0, 0}, {1, 1, 1}));
  vtkNew<vtkDoubleArray> f;
  f->SetName("f");
  for (vtkIdType i = 0; i < grid->GetNumberOfPoints(); ++i) f->InsertNextValue(grid->GetPoint(i)[0]);
  grid->GetPointData()->AddArray(f);
  vtkNew<vtkXMLUnstructuredGridWriter> writer;
  writer->SetFileName(path.string().c_str());
  writer->SetInputData(grid);
  ASSERT_EQ(writer->Write(), 1);
}

TEST(Replay, MeshIsRepublishedOnlyWhenItChanges) {
  test::TempDir tmp("topology");
  write_block_vtu(tmp.path() / "a.vtu", 2);
  write_block_vtu(tmp.path() / "b.vtu", 3);
  std::ofstream(tmp.path() / "run.series")
      << R"({"files":[{"name":"a.vtu","time":0},{"name":"a.vtu","time":1},{"name":"b.vtu","time":2},)"
      << R"({"name":"b.vtu","time":3}]})";
  const fs::path db = tmp.path() / "db";
  const Result r = replay_run({config(db, "f"), (tmp.path() / "run.series").string()});
  ASSERT_EQ(r.rc, 0) << r.err;
  EXPECT_NE(r.out.find("4 step(s) executed, mesh published 2 time(s)"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("mesh v2"), std::string::npos) << r.out;
  EXPECT_EQ(read_lines(db / "data.csv").size(), 5u);
}

TEST(Replay, ACorruptStepIsReportedAndTheRestStillRun) {
  test::TempDir tmp("corrupt");
  write_block_vtu(tmp.path() / "a.vtu", 2);
  std::ofstream(tmp.path() / "bad.vtu") << "<VTKFile type=\"UnstructuredGrid\"> truncated";
  std::ofstream(tmp.path() / "run.series")
      << R"({"files":[{"name":"a.vtu","time":0},{"name":"bad.vtu","time":1},{"name":"a.vtu","time":2}]})";
  const fs::path db = tmp.path() / "db";
  const Result r = replay_run({config(db, "f"), (tmp.path() / "run.series").string(), "--quiet"});
  EXPECT_EQ(r.rc, 1);
  EXPECT_NE(r.err.find("step 1: "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("bad.vtu"), std::string::npos) << r.err;
  EXPECT_EQ(read_lines(db / "data.csv").size(), 3u) << "steps 0 and 2 are in the database";
}

TEST(Replay, SurfaceMeshIsRefused) {
  test::TempDir tmp("blow");
  const Result r = replay_run({config(tmp.path() / "db", "thickness0"), (test::data_dir() / "blow.vtk").string()});
  EXPECT_EQ(r.rc, 1);
  EXPECT_NE(r.err.find("no volume cells"), std::string::npos) << r.err;
}

TEST(Replay, BadArgumentsAndInputsFailCleanly) {
  test::TempDir tmp("args");
  const std::string cfg = config(tmp.path() / "db", "Pressure");
  const std::string post = (test::data_dir() / "post.vtk").string();
  EXPECT_EQ(replay_run({}).rc, 2);
  EXPECT_EQ(replay_run({cfg}).rc, 2);
  EXPECT_EQ(replay_run({cfg, post, "--bogus"}).rc, 2);
  EXPECT_EQ(replay_run({cfg, post, "--steps", "1:2"}).rc, 2);  // post.vtk has one step
  EXPECT_EQ(replay_run({cfg, post, "--steps", "x"}).rc, 2);
  EXPECT_EQ(replay_run({"--help"}).rc, 0);
  const Result missing = replay_run({cfg, (tmp.path() / "missing.vtu").string()});
  EXPECT_EQ(missing.rc, 1);
  EXPECT_NE(missing.err.find("does not exist"), std::string::npos) << missing.err;
  const Result bad_config = replay_run({"{\"output\":{}}", post});
  EXPECT_EQ(bad_config.rc, 1);
  EXPECT_NE(bad_config.err.find("config"), std::string::npos) << bad_config.err;
}

}  // namespace
}  // namespace penumbra

namespace penumbra {
namespace {

// A run keeps its history (config "store"); penumbra-replay renders it again from the store with
// another config, as after the run: same steps, times and cycles, pictures within the bound.
TEST(ReplayStore, RerendersTheCompressedHistoryWithANewConfig) {
  test::TempDir tmp("store");
  const fs::path db1 = tmp.path() / "db1", db2 = tmp.path() / "db2", store = tmp.path() / "store";
  std::string with_store = config(db1, "diffused");
  with_store.pop_back();
  with_store += R"(,"store":{"directory":")" + store.string() + R"(","window":8,"error_bound":{"relative":0.001}}})";
  const Result first = replay_run({with_store, (test::data_dir() / "mug.e").string(), "--quiet"});
  ASSERT_EQ(first.rc, 0) << first.err;
  ASSERT_TRUE(fs::exists(store / "segment-000" / "diffused.pnbf"));

  const Result again = replay_run({config(db2, "diffused"), store.string()});
  ASSERT_EQ(again.rc, 0) << again.err;
  EXPECT_NE(again.out.find("21 step(s), 0 failure(s)"), std::string::npos) << again.out;
  const auto rows1 = read_lines(db1 / "data.csv"), rows2 = read_lines(db2 / "data.csv");
  ASSERT_EQ(rows2.size(), 22u);
  ASSERT_EQ(rows1.size(), rows2.size());
  for (std::size_t i = 0; i < rows1.size(); ++i) EXPECT_EQ(rows1[i], rows2[i]) << "same times, cycles and files";
  // The field comes back within 0.1 % of its range at every value: the same picture up to a
  // few 8-bit steps where colour or opacity change fastest.
  const std::string file = rows1[12].substr(rows1[12].rfind(',') + 1);
  int w1 = 0, h1 = 0, w2 = 0, h2 = 0;
  const auto a = render::read_png_rgb((db1 / file).string(), w1, h1);
  const auto b = render::read_png_rgb((db2 / file).string(), w2, h2);
  ASSERT_EQ(a.size(), b.size());
  EXPECT_LT(render::rms_difference_pct(a, b), 0.5);

  // A store that is not one is refused clearly.
  fs::create_directories(tmp.path() / "empty" / "segment-000");
  const Result bad = replay_run({config(tmp.path() / "db3", "diffused"), (tmp.path() / "empty").string()});
  EXPECT_EQ(bad.rc, 1);
  EXPECT_NE(bad.err.find("mesh.pnbm"), std::string::npos) << bad.err;
}

// A run whose mesh changed topology keeps one segment per topology; the replay renders every
// segment in order, --steps counting through them.
TEST(ReplayStore, EverySegmentReplaysInOrder) {
  test::TempDir tmp("segments");
  write_block_vtu(tmp.path() / "a.vtu", 3);
  write_block_vtu(tmp.path() / "b.vtu", 4);
  std::ofstream(tmp.path() / "run.series") << R"({"files":[{"name":"a.vtu","time":0},{"name":"a.vtu","time":1},)"
                                           << R"({"name":"b.vtu","time":2},{"name":"b.vtu","time":3}]})";
  const fs::path db1 = tmp.path() / "db1", store = tmp.path() / "store";
  std::string with_store = config(db1, "f");
  with_store.pop_back();
  with_store += R"(,"store":{"directory":")" + store.string() + R"(","window":8}})";
  const Result first = replay_run({with_store, (tmp.path() / "run.series").string(), "--quiet"});
  ASSERT_EQ(first.rc, 0) << first.err;
  ASSERT_TRUE(fs::exists(store / "segment-001"));
  const fs::path db2 = tmp.path() / "db2";
  const Result again = replay_run({config(db2, "f"), store.string()});
  ASSERT_EQ(again.rc, 0) << again.err;
  EXPECT_NE(again.out.find("2 segment(s), 4 step(s)"), std::string::npos) << again.out;
  EXPECT_EQ(read_lines(db1 / "data.csv"), read_lines(db2 / "data.csv"));
  const fs::path db3 = tmp.path() / "db3";
  const Result span = replay_run({config(db3, "f"), store.string(), "--steps", "1:3", "--quiet"});
  ASSERT_EQ(span.rc, 0) << span.err;
  const auto rows = read_lines(db3 / "data.csv");
  ASSERT_EQ(rows.size(), 3u);
  EXPECT_EQ(rows[1].substr(0, 2), "1,");
  EXPECT_EQ(rows[2].substr(0, 2), "2,");
}

#ifdef PNB_LAGRANGIAN_EXAMPLE
// The Lagrangian example's history (one segment, its coordinates and fields per cycle) replays
// with the example's own render settings: the same rows, and pictures within the stored bounds.
TEST(ReplayStore, TheLagrangianExamplesHistoryReplays) {
  test::TempDir tmp("lagrangian");
  const fs::path db1 = tmp.path() / "db1", store = tmp.path() / "history", db2 = tmp.path() / "db2";
  const std::string command =
      std::string(PNB_LAGRANGIAN_EXAMPLE) + " '" + db1.string() + "' '" + store.string() + "' > /dev/null";
  ASSERT_EQ(std::system(command.c_str()), 0);
  EXPECT_FALSE(fs::exists(store / "segment-001"));
  const std::string settings = R"({"output":{"directory":")" + db2.string() + R"("},
      "image": {"width": 128, "height": 128, "background": [0.08, 0.08, 0.1]},
      "cameras": {"phi": [-60, 30], "theta": [55], "fov": 30},
      "fields": [{"name": "temperature", "range": [0, 1], "transfer_function": {
          "colors": [[0, 0.1, 0.2, 0.5], [0.5, 0.9, 0.4, 0.1], [1, 1, 1, 0.7]],
          "opacities": [[0, 0.5], [0.2, 2], [1, 14]]}},
        {"name": "speed", "range": [0, 1.1], "transfer_function": {
          "colors": [[0, 0.1, 0.3, 0.6], [1, 1, 0.9, 0.3]], "opacities": [[0, 0.3], [1, 6]]}}],
      "trigger": {"every_cycles": 8}})";
  const Result r = replay_run({settings, store.string()});
  ASSERT_EQ(r.rc, 0) << r.err;
  EXPECT_NE(r.out.find("96 step(s), 0 failure(s)"), std::string::npos) << r.out;
  const auto rows1 = read_lines(db1 / "data.csv"), rows2 = read_lines(db2 / "data.csv");
  ASSERT_EQ(rows1, rows2);
  ASSERT_EQ(rows1.size(), 1u + 12 * 2 * 2);
  // The coordinates within 1/64 of the thinnest cell's altitude and the fields within 0.1 % of
  // their range: RMS well under a percent of 255 on every image.
  for (std::size_t i = 1; i < rows1.size(); ++i) {
    const std::string file = rows1[i].substr(rows1[i].rfind(',') + 1);
    int w1 = 0, h1 = 0, w2 = 0, h2 = 0;
    const auto a = render::read_png_rgb((db1 / file).string(), w1, h1);
    const auto b = render::read_png_rgb((db2 / file).string(), w2, h2);
    ASSERT_EQ(a.size(), b.size());
    EXPECT_LT(render::rms_difference_pct(a, b), 0.5) << file;
  }
}
#endif

}  // namespace
}  // namespace penumbra

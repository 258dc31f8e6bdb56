// SPDX-License-Identifier: BSD-3-Clause
// tests/unit/insitu/cinema_database_test.cpp -- data.csv layout, resume, refuse, I/O errors
#include <gtest/gtest.h>

#include "cinema_database.h"
#include "penumbra/core/error.h"
#include "test_util.h"

namespace penumbra::insitu {
namespace {

using testing::read_text;
using testing::TempDir;
const std::vector<std::string> kParams = {"time", "phi", "theta", "field"};

CinemaDatabase::Row row(std::string time, std::string field, std::string file) {
  return {{std::move(time), "0", "30", std::move(field)}, std::move(file)};
}

TEST(CinemaDatabase, CreatesDirectoryWithHeaderOnlyCsv) {
  TempDir tmp;
  const std::string dir = tmp / "a/b/db.cdb";
  CinemaDatabase db(dir, kParams, IfExists::error);
  EXPECT_EQ(read_text(dir + "/data.csv"), "time,phi,theta,field,FILE\n");
  EXPECT_TRUE(db.rows().empty());
}

TEST(CinemaDatabase, CommitAppendsRowsAndQuotesWhenNeeded) {
  TempDir tmp;
  CinemaDatabase db(tmp / "db", kParams, IfExists::error);
  db.commit({row("0", "T", "T/a.png"), row("0", "p,q", "p_q/a.png")});
  db.commit({row("0.5", "say \"hi\"", "x/b.png")});
  EXPECT_EQ(read_text(tmp / "db/data.csv"),
            "time,phi,theta,field,FILE\n0,0,30,T,T/a.png\n0,0,30,\"p,q\",p_q/a.png\n0.5,0,30,\"say \"\"hi\"\"\",x/b.png\n");
  const auto table = CinemaDatabase::parse_csv(read_text(tmp / "db/data.csv"), "test");
  ASSERT_EQ(table.size(), 4u);
  EXPECT_EQ(table[2][3], "p,q");
  EXPECT_EQ(table[3][3], "say \"hi\"");
}

TEST(CinemaDatabase, SameParametersReplaceTheRow) {
  TempDir tmp;
  CinemaDatabase db(tmp / "db", kParams, IfExists::error);
  db.commit({row("1", "T", "T/old.png"), row("1", "U", "U/old.png")});
  db.commit({row("1", "T", "T/new.png")});
  ASSERT_EQ(db.rows().size(), 2u);
  EXPECT_EQ(db.rows()[0].file, "T/new.png");
  EXPECT_EQ(db.rows()[1].file, "U/old.png");
}

TEST(CinemaDatabase, ImagePathsNeverReuseAFile) {
  TempDir tmp;
  CinemaDatabase db(tmp / "db", kParams, IfExists::error);
  const std::string a = db.new_image_path("T", "c000001_phi0");
  EXPECT_EQ(a, "T/c000001_phi0.png");
  EXPECT_EQ(db.new_image_path("T", "c000001_phi0"), "T/c000001_phi0_2.png");  // reserved in this step
  db.commit({});
  std::ofstream(db.path_of(a)) << "x";
  EXPECT_EQ(db.new_image_path("T", "c000001_phi0"), "T/c000001_phi0_2.png");  // exists on disk
  EXPECT_EQ(db.new_image_path("a/../b", "x y"), "a_.._b/x_y.png");
}

TEST(CinemaDatabase, SafePathComponent) {
  EXPECT_EQ(safe_path_component("temp-1.x_y"), "temp-1.x_y");
  EXPECT_EQ(safe_path_component("a/b c"), "a_b_c");
  EXPECT_EQ(safe_path_component(""), "_");
  EXPECT_EQ(safe_path_component(".."), "_..");
}

TEST(CinemaDatabase, ErrorModeRefusesNonEmptyDirectoryAndAcceptsEmptyOne) {
  TempDir tmp;
  std::filesystem::create_directories(tmp / "empty");
  EXPECT_NO_THROW(CinemaDatabase(tmp / "empty", kParams, IfExists::error));
  std::filesystem::create_directories(tmp / "used");
  std::ofstream(tmp / "used/notes.txt") << "keep me";
  try {
    CinemaDatabase db(tmp / "used", kParams, IfExists::error);
    FAIL() << "non-empty directory accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::invalid_argument);
    EXPECT_NE(std::string(e.what()).find("exists and is not empty"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("if_exists"), std::string::npos) << e.what();
  }
  EXPECT_EQ(read_text(tmp / "used/notes.txt"), "keep me");
  EXPECT_FALSE(std::filesystem::exists(tmp / "used/data.csv"));
}

TEST(CinemaDatabase, ResumeAppendsToExistingRows) {
  TempDir tmp;
  {
    CinemaDatabase db(tmp / "db", kParams, IfExists::error);
    db.commit({row("0", "T", "T/a.png"), row("1", "T", "T/b.png")});
  }
  CinemaDatabase db(tmp / "db", kParams, IfExists::resume);
  ASSERT_EQ(db.rows().size(), 2u);
  db.commit({row("2", "T", "T/c.png"), row("1", "T", "T/b2.png")});
  EXPECT_EQ(read_text(tmp / "db/data.csv"),
            "time,phi,theta,field,FILE\n0,0,30,T,T/a.png\n1,0,30,T,T/b2.png\n2,0,30,T,T/c.png\n");
}

TEST(CinemaDatabase, ResumeRemovesTemporaryFilesOfAKilledWriter) {
  TempDir tmp;
  { CinemaDatabase db(tmp / "db", kParams, IfExists::error); }
  std::filesystem::create_directories(tmp / "db/T");
  for (const char* f : {"db/data.csv.tmp.123", "db/T/c000001_phi0.png.tmp.77", "db/T/keep.tmp.x", "db/T/keep.png"})
    std::ofstream(tmp / f) << "x";
  CinemaDatabase db(tmp / "db", kParams, IfExists::resume);
  EXPECT_FALSE(std::filesystem::exists(tmp / "db/data.csv.tmp.123"));
  EXPECT_FALSE(std::filesystem::exists(tmp / "db/T/c000001_phi0.png.tmp.77"));
  EXPECT_TRUE(std::filesystem::exists(tmp / "db/T/keep.tmp.x"));
  EXPECT_TRUE(std::filesystem::exists(tmp / "db/T/keep.png"));
}

TEST(CinemaDatabase, ResumeOfNonDatabaseDirectoryStartsFresh) {
  TempDir tmp;
  std::filesystem::create_directories(tmp / "db");
  std::ofstream(tmp / "db/readme") << "x";
  CinemaDatabase db(tmp / "db", kParams, IfExists::resume);
  EXPECT_TRUE(db.rows().empty());
  EXPECT_EQ(read_text(tmp / "db/readme"), "x");
}

TEST(CinemaDatabase, ResumeRejectsMismatchedHeader) {
  TempDir tmp;
  { CinemaDatabase db(tmp / "db", kParams, IfExists::error); }
  const std::string before = read_text(tmp / "db/data.csv");
  try {
    CinemaDatabase db(tmp / "db", {"time", "phi", "theta", "camera", "field"}, IfExists::resume);
    FAIL() << "mismatched header accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::invalid_argument);
    EXPECT_NE(std::string(e.what()).find("its header is 'time,phi,theta,field,FILE' but this config writes "
                                         "'time,phi,theta,camera,field,FILE'"),
              std::string::npos)
        << e.what();
  }
  EXPECT_EQ(read_text(tmp / "db/data.csv"), before);  // untouched
}

TEST(CinemaDatabase, ResumeRejectsCorruptCsv) {
  TempDir tmp;
  std::filesystem::create_directories(tmp / "db");
  std::ofstream(tmp / "db/data.csv") << "time,phi,theta,field,FILE\n0,0,30,T\n";
  EXPECT_THROW(CinemaDatabase(tmp / "db", kParams, IfExists::resume), Error);
}

TEST(CinemaDatabase, UnwritableDirectoryIsAnIoErrorNamingThePath) {
  TempDir tmp;
  // A regular file as parent defeats directory creation even for root, unlike permission bits.
  std::ofstream(tmp / "file") << "x";
  const std::string dir = tmp / "file/db";
  try {
    CinemaDatabase db(dir, kParams, IfExists::error);
    FAIL() << "unwritable directory accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::io_error);
    EXPECT_NE(std::string(e.what()).find(dir), std::string::npos) << e.what();
  }
  try {
    CinemaDatabase db(tmp / "file", kParams, IfExists::resume);
    FAIL() << "a file accepted as output directory";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::io_error);
    EXPECT_NE(std::string(e.what()).find("is not a directory"), std::string::npos) << e.what();
  }
}

TEST(CinemaDatabase, ParseCsvRejectsMalformedText) {
  EXPECT_EQ(CinemaDatabase::parse_csv("a,b\r\n1,\"x\ny\"\n", "t").at(1).at(1), "x\ny");
  EXPECT_THROW(CinemaDatabase::parse_csv("a,b\n1\n", "t"), Error);
  EXPECT_THROW(CinemaDatabase::parse_csv("a,b\n1,\"x\n", "t"), Error);
  EXPECT_THROW(CinemaDatabase::parse_csv("a,b\n1,x\"y\"\n", "t"), Error);
}

}  // namespace
}  // namespace penumbra::insitu

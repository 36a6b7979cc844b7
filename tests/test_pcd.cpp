// The PCD reader (PCL's format): hand-written ascii, binary and binary_compressed files
// against their known points, Open3D's files read back equal, malformed files refused naming
// the line or field.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include "expect_error.hpp"
#include "softhd/error.hpp"
#include "softhd/io/cloud_io.hpp"

using softhd::FileError;
using softhd::PointCloud;
using softhd::test::expect_error;
using Notes = std::vector<std::string>;

namespace {

const std::string kHeader3 =
    "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n";

template <class T>
void put(std::string& out, T v) {
  char b[sizeof(T)];
  std::memcpy(b, &v, sizeof(T));
  out.append(b, sizeof(T));
}

bool mentions(const Notes& notes, const std::string& what) {
  for (const std::string& n : notes)
    if (n.find(what) != std::string::npos) return true;
  return false;
}

std::string data_dir() { return std::string(SOFTHD_SOURCE_DIR) + "/tests/data/pcd/"; }

}  // namespace

TEST(PcdReader, AsciiWithSkippedFieldsAndWeights) {
  const std::string file =
      "# a comment\nVERSION .7\nFIELDS x y z rgb weight normal_x\nSIZE 4 4 4 4 8 4\n"
      "TYPE F F F U F F\nCOUNT 1 1 1 1 1 1\nWIDTH 4\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\n"
      "POINTS 4\nDATA ascii\n1 2 3 4278190080 0.5 0\n-1.5 0.25 1e3 0 2 1\n\n"
      "nan nan nan 0 1 0\n0.1 0.2 0.3 1 0.125 nan\n";
  Notes notes;
  const PointCloud c = softhd::parse_pcd_cloud(file, "a.pcd", &notes);
  ASSERT_EQ(c.size(), 3);
  EXPECT_EQ(c.dim(), 3);
  EXPECT_EQ(c.points().row(0), Eigen::RowVector3d(1, 2, 3));
  EXPECT_EQ(c.points().row(1), Eigen::RowVector3d(-1.5, 0.25, 1000));
  EXPECT_EQ(c.points().row(2), Eigen::RowVector3d(0.1, 0.2, 0.3));
  EXPECT_EQ(c.volumes(), Eigen::Vector3d(0.5, 2, 0.125));
  EXPECT_TRUE(mentions(notes, "a.pcd: fields rgb, normal_x ignored")) << notes.size();
  EXPECT_TRUE(mentions(notes, "1 invalid points"));
}

TEST(PcdReader, BinaryOfMixedTypes) {
  // x F8, y F4, z I2, an unsigned U1 × 3 colour, volume F4.
  std::string file =
      "VERSION 0.7\nFIELDS x y z rgb volume\nSIZE 8 4 2 1 4\nTYPE F F I U F\nCOUNT 1 1 1 3 1\n"
      "WIDTH 2\nHEIGHT 1\nPOINTS 2\nDATA binary\n";
  put(file, 0.1), put(file, 2.5f), put(file, std::int16_t(-7)), file += "abc", put(file, 3.0f);
  put(file, -4.0), put(file, 0.0f), put(file, std::int16_t(300)), file += "def", put(file, 0.5f);
  const PointCloud c = softhd::parse_pcd_cloud(file, "b.pcd");
  ASSERT_EQ(c.size(), 2);
  EXPECT_EQ(c.points().row(0), Eigen::RowVector3d(0.1, 2.5, -7));
  EXPECT_EQ(c.points().row(1), Eigen::RowVector3d(-4, 0, 300));
  EXPECT_EQ(c.volumes(), Eigen::Vector2d(3, 0.5));
}

TEST(PcdReader, BinaryCompressedWithABackReference) {
  // Four points of x y z intensity (F 4), stored field after field: 64 bytes, the 16 bytes of
  // one field repeated four times. LZF: a literal run of 16 (control 15), then a reference of
  // length 48 = 7 + 39 + 2 at offset 16 (control 0xE0, length byte 39, offset byte 15).
  const float v[4] = {1.5f, -2.0f, 0.25f, 8.0f};
  std::string lzf(1, char(15));
  for (float f : v) put(lzf, f);
  lzf += "\xE0\x27\x0F";
  std::string file = kHeader3;
  file.replace(file.find("FIELDS x y z"), 12, "FIELDS x y z intensity");
  file.replace(file.find("SIZE 4 4 4"), 10, "SIZE 4 4 4 4");
  file.replace(file.find("TYPE F F F"), 10, "TYPE F F F F");
  file.replace(file.find("COUNT 1 1 1"), 11, "COUNT 1 1 1 1");
  file += "WIDTH 4\nHEIGHT 1\nPOINTS 4\nDATA binary_compressed\n";
  put(file, std::uint32_t(lzf.size())), put(file, std::uint32_t(64));
  file += lzf;
  Notes notes;
  const PointCloud c = softhd::parse_pcd_cloud(file, "c.pcd", &notes);
  ASSERT_EQ(c.size(), 4);
  for (int i = 0; i < 4; ++i) EXPECT_EQ(c.points().row(i), Eigen::RowVector3d::Constant(v[i]));
  EXPECT_TRUE(mentions(notes, "fields intensity ignored"));
  // A reference reaching before the start, and a size the data do not fill, are refused.
  std::string bad = file;
  bad[bad.size() - 1] = char(40);
  expect_error<FileError>([&] { softhd::parse_pcd_cloud(bad, "c.pcd"); },
                          "c.pcd: corrupt binary_compressed data: a reference before the start");
  bad = file;
  bad.resize(bad.size() - 3);
  bad.replace(bad.size() - 17 - 8, 4, std::string("\x11\0\0\0", 4));
  expect_error<FileError>([&] { softhd::parse_pcd_cloud(bad, "c.pcd"); }, "less data");
}

TEST(PcdReader, Open3dFilesReadBackEqual) {
  const PointCloud expected = softhd::read_text_cloud(data_dir() + "open3d_points.txt");
  for (const char* name : {"binary", "compressed", "ascii"}) {
    Notes notes;
    const PointCloud c = softhd::read_cloud(data_dir() + "open3d_" + name + ".pcd", 0, &notes);
    ASSERT_EQ(c.size(), expected.size()) << name;
    // Binary files hold the float32 values exactly. Open3D's ascii writer prints the original
    // doubles to 10 significant digits: within half a float32 ulp (2.4e-7 for |x| < 4) plus
    // 1.5e-9 of the reference.
    const double tol = std::string(name) == "ascii" ? 2.4e-7 + 1.5e-9 : 0.0;
    EXPECT_LE((c.points() - expected.points()).cwiseAbs().maxCoeff(), tol) << name;
    EXPECT_EQ(c.volumes(), Eigen::VectorXd::Ones(c.size()));
    EXPECT_TRUE(mentions(notes, "fields normal_x, normal_y, normal_z, rgb ignored")) << name;
  }
}

TEST(PcdReader, RefusesMalformedFilesNamingTheLine) {
  struct Case {
    std::string file, message;
  };
  const std::string tail = "WIDTH 1\nHEIGHT 1\nPOINTS 1\nDATA ascii\n1 2 3\n";
  const std::vector<Case> cases = {
      {"FIELDS x y z\nSIZE 4 4\n", "m.pcd:2: SIZE has 2 values for 3 fields"},
      {"FIELDS x y z\nSIZE 4 4 4\nTYPE F F D\n" + tail, "m.pcd:3: unknown TYPE 'D'"},
      {"FIELDS x y z\nSIZE 4 4 3\nTYPE F F F\n" + tail, "m.pcd:7: field 'z': type F cannot"},
      {"FIELDS x y\nSIZE 4 4\nTYPE F F\n" + tail, "m.pcd: the FIELDS line needs x, y and z"},
      {kHeader3 + "WIDTH 2\nHEIGHT 1\nPOINTS 3\nDATA ascii\n", "m.pcd:10: WIDTH x HEIGHT = 2"},
      {kHeader3 + "WIDTH 4294967296\nHEIGHT 4294967297\nPOINTS 4294967296\nDATA ascii\n",
       "m.pcd:10: WIDTH x HEIGHT = 4294967296 x 4294967297 is too large"},
      {kHeader3 + "WIDTH 1\nPOINTS 1\n", "m.pcd: missing DATA line"},
      {kHeader3 + "WIDTH 1\nDATA lzf\n", "m.pcd:8: unknown DATA 'lzf'"},
      {kHeader3 + "COLOUR 1\n", "m.pcd:7: unexpected header line starting with 'COLOUR'"},
      {kHeader3 + "WIDTH x\n", "m.pcd:7: invalid WIDTH 'x'"},
      {kHeader3 + "WIDTH 2\nDATA ascii\n1 2 3\n4 5\n", "m.pcd:10: expected 3 values, got 2"},
      {kHeader3 + "WIDTH 1\nDATA ascii\n1 2 abc\n", "m.pcd:9: expected a number (z), got 'abc'"},
      {kHeader3 + "WIDTH 1\nDATA ascii\n1 nan 3\n", "m.pcd:9: non-finite coordinate (y)"},
      {kHeader3 + "WIDTH 2\nDATA ascii\n1 2 3\n", "m.pcd: the file has 1 points, POINTS says 2"},
      {kHeader3 + "WIDTH 1\nDATA ascii\n1 2 3\n4 5 6\n", "m.pcd:10: more points than POINTS"},
      {kHeader3 + "WIDTH 3\nDATA binary\n12345678", "m.pcd: truncated binary data: 8 bytes"},
      {kHeader3 + "WIDTH 0\nDATA ascii\n", "m.pcd: no points in the file"},
      {"", "m.pcd: empty file"},
  };
  for (const Case& c : cases)
    expect_error<FileError>([&] { softhd::parse_pcd_cloud(c.file, "m.pcd"); }, c.message);
  // A PCD cloud is 3D: read_cloud with dim 2 refuses it.
  const std::string path = testing::TempDir() + "/flat.pcd";
  std::ofstream(path) << kHeader3 << tail;
  EXPECT_EQ(softhd::read_cloud(path).size(), 1);
  expect_error<FileError>([&] { softhd::read_cloud(path, 2); }, "3D cloud but dim=2");
}

TEST(PlyReader, NamesSkippedPropertiesInANote) {
  const std::string ply =
      "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
      "property float z\nproperty uchar red\nproperty float nx\nend_header\n1 2 3 255 0.5\n";
  Notes notes;
  EXPECT_EQ(softhd::parse_ply_cloud(ply, "n.ply", &notes).size(), 1);
  EXPECT_TRUE(mentions(notes, "n.ply: vertex properties red, nx ignored"));
}

TEST(TextReader, SkipsColourAndNormalColumnsWithANote) {
  Notes notes;
  const PointCloud c =
      softhd::parse_text_cloud("1 2 3 255 0 0\n4 5 6 0 255 0\n", "c.txt", 0, &notes);
  ASSERT_EQ(c.size(), 2);
  EXPECT_EQ(c.points().row(1), Eigen::RowVector3d(4, 5, 6));
  EXPECT_EQ(c.volumes(), Eigen::Vector2d(1, 1));
  EXPECT_TRUE(mentions(notes, "c.txt: columns 4 to 6 (colours or normals) ignored"));
  notes.clear();
  const PointCloud v = softhd::parse_text_cloud("1 2 3 0.5 0 0 1 9 9 9\n", "v.txt", 3, &notes);
  EXPECT_EQ(v.volumes()[0], 0.5);
  EXPECT_TRUE(mentions(notes, "v.txt: columns 5 to 10"));
  expect_error<FileError>([] { softhd::parse_text_cloud("1 2 3 4 5 6 7 8\n", "e.txt"); },
                          "e.txt:1: expected 2, 3 or 4 columns");
}

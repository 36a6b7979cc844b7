#include <gtest/gtest.h>
#include <signal.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <random>
#include <string>

#include "expect_error.hpp"
#include "softhd/error.hpp"
#include "softhd/io/atomic_file.hpp"
#include "softhd/io/cloud_io.hpp"
#include "softhd/point_cloud.hpp"

namespace fs = std::filesystem;
using softhd::FileError;
using softhd::InvalidArgument;
using softhd::PointCloud;
using softhd::test::expect_error;

namespace {

// Each test gets a fresh, empty directory for its files.
class CloudIo : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::path(::testing::TempDir()) /
           ("softhd_io_" + std::to_string(::getpid()) + "_" + info->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // Writes `content` (bytes, as is) to `name` in the test directory; returns its path.
  std::string write(const std::string& name, const std::string& content) const {
    const std::string path = (dir_ / name).string();
    std::ofstream out(path, std::ios::binary);
    out << content;
    return path;
  }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }

  fs::path dir_;
};

// Bitwise equality of two clouds (distinguishes -0.0 from 0.0).
void expect_bit_equal(const PointCloud& a, const PointCloud& b) {
  ASSERT_EQ(a.dim(), b.dim());
  ASSERT_EQ(a.size(), b.size());
  EXPECT_EQ(std::memcmp(a.points().data(), b.points().data(),
                        sizeof(double) * static_cast<std::size_t>(a.points().size())),
            0);
  EXPECT_EQ(std::memcmp(a.volumes().data(), b.volumes().data(),
                        sizeof(double) * static_cast<std::size_t>(a.size())),
            0);
}

// A cloud with awkward values: 1/3, 0.1, -0.0, subnormals, huge and tiny magnitudes.
PointCloud awkward_cloud(int dim, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  const int n = 50;
  Eigen::MatrixXd p(n, dim);
  Eigen::VectorXd v(n);
  for (int i = 0; i < n; ++i) {
    for (int k = 0; k < dim; ++k) {
      const double u = static_cast<double>(rng() >> 11) * 0x1.0p-53;
      p(i, k) = (u - 0.5) * std::pow(10.0, static_cast<int>(rng() % 40) - 20);
    }
    v[i] = static_cast<double>((rng() >> 11) + 1) * 0x1.0p-50;
  }
  p(0, 0) = 1.0 / 3.0;
  p(0, 1) = 0.1;
  p(1, 0) = -0.0;
  p(1, 1) = std::numeric_limits<double>::denorm_min();
  p(2, 0) = std::numeric_limits<double>::max();
  p(2, 1) = -std::numeric_limits<double>::min();
  v[0] = std::numeric_limits<double>::denorm_min();
  v[1] = 1e300;
  return PointCloud(p, v);
}

// Little-endian bytes of `value`.
template <class T>
std::string le(T value) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_BIG_ENDIAN__
  std::reverse(bytes, bytes + sizeof(T));
#endif
  return std::string(bytes, sizeof(T));
}

}  // namespace

// ----------------------------------------------------------------------------
// Text

TEST_F(CloudIo, TextParsesHandWrittenFile) {
  const std::string file = write("c.txt",
                                 "# a comment line\n"
                                 "\n"
                                 "1 2 3 0.5   # trailing comment\n"
                                 "  -1.5,\t2.5e1 , +3, 4\r\n"
                                 "\t \n"
                                 "8 .5 5. 1e-3\n"
                                 "# done");
  const PointCloud c = softhd::read_cloud(file);
  ASSERT_EQ(c.dim(), 3);
  ASSERT_EQ(c.size(), 3);
  Eigen::MatrixXd p(3, 3);
  p << 1, 2, 3, -1.5, 25, 3, 8, 0.5, 5;
  Eigen::VectorXd v(3);
  v << 0.5, 4, 1e-3;
  EXPECT_EQ(c.points(), p);
  EXPECT_EQ(c.volumes(), v);
}

TEST_F(CloudIo, TextColumnRules) {
  const std::string two = write("two.txt", "1 2\n3 4\n");
  const std::string three = write("three.txt", "1 2 3\n4 5 6\n");
  const std::string four = write("four.txt", "1 2 3 4\n5 6 7 8\n");

  PointCloud c = softhd::read_cloud(two);  // auto: 2 columns -> 2D, V = 1
  EXPECT_EQ(c.dim(), 2);
  EXPECT_EQ(c.volumes(), Eigen::VectorXd::Ones(2));
  EXPECT_EQ(c.points()(1, 1), 4.0);
  c = softhd::read_cloud(two, 2);
  EXPECT_EQ(c.dim(), 2);

  c = softhd::read_cloud(three);  // auto: 3 columns -> 3D, V = 1
  EXPECT_EQ(c.dim(), 3);
  EXPECT_EQ(c.points()(1, 2), 6.0);
  EXPECT_EQ(c.volumes(), Eigen::VectorXd::Ones(2));
  c = softhd::read_cloud(three, 3);
  EXPECT_EQ(c.dim(), 3);
  EXPECT_EQ(c.volumes(), Eigen::VectorXd::Ones(2));
  c = softhd::read_cloud(three, 2);  // dim 2: x y V
  EXPECT_EQ(c.dim(), 2);
  EXPECT_EQ(c.points()(1, 1), 5.0);
  EXPECT_EQ(c.volumes()[1], 6.0);

  for (int dim : {0, 3}) {  // 4 columns -> 3D with V
    c = softhd::read_cloud(four, dim);
    EXPECT_EQ(c.dim(), 3);
    EXPECT_EQ(c.points()(1, 2), 7.0);
    EXPECT_EQ(c.volumes()[1], 8.0);
  }
}

TEST_F(CloudIo, TextRoundTripIsBitExact) {
  for (int dim : {2, 3}) {
    const PointCloud c = awkward_cloud(dim, 7 + dim);
    const std::string file = path("rt" + std::to_string(dim) + ".txt");
    softhd::write_text_cloud(file, c);
    expect_bit_equal(softhd::read_cloud(file, dim), c);

    softhd::write_text_cloud(file, c, false);
    const PointCloud without = softhd::read_cloud(file);
    expect_bit_equal(without, PointCloud(c.points()));
  }
}

TEST_F(CloudIo, TextWriterFormat) {
  Eigen::MatrixXd p(2, 2);
  p << 0.1, -2, 1e-300, 3;
  Eigen::VectorXd v(2);
  v << 0.25, 1.0 / 3.0;
  const std::string file = path("w.txt");
  softhd::write_text_cloud(file, PointCloud(p, v));
  std::ifstream in(file);
  std::string header, line1, line2;
  std::getline(in, header);
  std::getline(in, line1);
  std::getline(in, line2);
  EXPECT_EQ(header.rfind("# ", 0), 0u) << header;
  EXPECT_EQ(line1, "0.1 -2 0.25");
  EXPECT_EQ(line2, "1e-300 3 0.3333333333333333");
}

TEST_F(CloudIo, TextErrors) {
  const std::string missing = path("missing.txt");
  expect_error<FileError>([&] { softhd::read_cloud(missing); },
                          "cannot open '" + missing + "': No such file or directory");
  expect_error<FileError>([&] { softhd::read_cloud(dir_.string()); },
                          "cannot read '" + dir_.string() + "'");
  expect_error<InvalidArgument>([&] { softhd::read_cloud(missing, 4); }, "dim must be 0");

  struct Case {
    const char* content;
    int dim;
    const char* message;  // after "<path>:"
  };
  const Case cases[] = {
      {"1 2 3\n\n# c\n1 abc 3\n", 0, "4: expected a number, got 'abc'"},
      {"1 2 3.5x\n", 0, "1: expected a number, got '3.5x'"},
      {"1 2 3\n1 2 --3\n", 0, "2: expected a number, got '--3'"},
      {"1 +-2 3\n", 0, "1: expected a number, got '+-2'"},
      {"1 2 1e400\n", 0, "1: number out of the range of a double, got '1e400'"},
      {"1 nan 3\n", 0, "1: non-finite coordinate, got 'nan'"},
      {"1 2 -inf\n", 0, "1: non-finite coordinate, got '-inf'"},
      {"1 2 3 inf\n", 0, "1: non-finite volume, got 'inf'"},
      {"1 2 3 1\n1 2 3 0\n", 0, "2: volume must be > 0, got '0'"},
      {"1 2 -0.5\n", 2, "1: volume must be > 0, got '-0.5'"},
      {"1 2 3 nan\n", 3, "1: non-finite volume, got 'nan'"},
      {"# only\n7\n", 0,
       "2: expected 2, 3 or 4 columns (x y [z] [V]; in 3D 3 or 6 more may follow), got 1"},
      {"1 2 3 4 5\n", 0,
       "1: expected 2, 3 or 4 columns (x y [z] [V]; in 3D 3 or 6 more may follow), got 5"},
      {"1 2 3 4 5 6\n", 2, "1: expected 2 or 3 columns (x y [V]) for dim=2, got 6"},
      {"1 2 3 4\n", 2, "1: expected 2 or 3 columns (x y [V]) for dim=2, got 4"},
      {"1 2\n", 3,
       "1: expected 3 or 4 columns (x y z [V]; 3 or 6 more may follow) for dim=3, got 2"},
      {"# header\n1 2\n3 4\n\n5 6\n# x\n7 8 9\n", 0,
       "7: mixed dimensions: line 7 has 3 columns, line 2 had 2"},
      {"1 2 3\n1 2 3 4\n", 3, "2: mixed dimensions: line 2 has 4 columns, line 1 had 3"},
      {"1,,2\n", 0, "1: empty field (stray ',')"},
      {"1 2,\n", 0, "1: empty field (stray ',')"},
      {", 1 2\n", 0, "1: empty field (stray ',')"},
  };
  int i = 0;
  for (const Case& c : cases) {
    const std::string file = write("bad" + std::to_string(i++) + ".txt", c.content);
    SCOPED_TRACE(c.content);
    expect_error<FileError>([&] { softhd::read_cloud(file, c.dim); }, file + ":" + c.message);
  }

  const std::string empty = write("empty.txt", "");
  expect_error<FileError>([&] { softhd::read_cloud(empty); }, empty + ": no points in the file");
  const std::string comments = write("comments.txt", "# x y z\n\n   # nothing\n");
  expect_error<FileError>([&] { softhd::read_cloud(comments); },
                          comments + ": no points in the file");
}

TEST_F(CloudIo, WriteErrors) {
  const PointCloud c(Eigen::MatrixXd::Zero(2, 3));
  const std::string bad = path("no_such_dir/out.txt");
  expect_error<FileError>([&] { softhd::write_text_cloud(bad, c); },
                          "cannot write '" + bad + "': No such file or directory");
  expect_error<FileError>([&] { softhd::write_ply_cloud(bad, c); },
                          "cannot write '" + bad + "': No such file or directory");
}

// ----------------------------------------------------------------------------
// PLY

TEST_F(CloudIo, PlyAsciiHandWritten) {
  // A face element before and after the vertex element, extra scalar and list
  // properties, comments and obj_info, CRLF line ends in the header.
  const std::string file = write("h.ply",
                                 "ply\r\n"
                                 "format ascii 1.0\r\n"
                                 "comment made by hand\n"
                                 "obj_info anything at all\n"
                                 "element face 2\n"
                                 "property list uchar int vertex_indices\n"
                                 "property float quality\n"
                                 "element vertex 3\n"
                                 "property uchar red\n"
                                 "property float x\n"
                                 "property list ushort float normals\n"
                                 "property float y\n"
                                 "property double volume\n"
                                 "property float z\n"
                                 "element edge 1\n"
                                 "property int a\n"
                                 "property int b\n"
                                 "end_header\n"
                                 "3 0 1 2 0.5\n"
                                 "0 7.25\n"
                                 "255 1.5 2 0.1 0.2 2.5 0.125 3.5\n"
                                 "0 -1 0 -2 4 -3\n"
                                 "7 1e-3 3 1 2 3 0 1 0.5\n"
                                 "0 1\n");
  const PointCloud c = softhd::read_cloud(file);
  ASSERT_EQ(c.dim(), 3);
  ASSERT_EQ(c.size(), 3);
  Eigen::MatrixXd p(3, 3);
  p << 1.5, 2.5, 3.5, -1, -2, -3, 1e-3, 0, 0.5;
  Eigen::VectorXd v(3);
  v << 0.125, 4, 1;
  EXPECT_EQ(c.points(), p);
  EXPECT_EQ(c.volumes(), v);
}

TEST_F(CloudIo, PlyAscii2DWithoutVolume) {
  const std::string file = write("flat.PLY",
                                 "ply\nformat ascii 1.0\nelement vertex 2\n"
                                 "property double x\nproperty double y\nend_header\n"
                                 "1 2\n3 4\n");
  const PointCloud c = softhd::read_cloud(file);
  ASSERT_EQ(c.dim(), 2);
  Eigen::MatrixXd p(2, 2);
  p << 1, 2, 3, 4;
  EXPECT_EQ(c.points(), p);
  EXPECT_EQ(c.volumes(), Eigen::VectorXd::Ones(2));
  EXPECT_EQ(softhd::read_cloud(file, 2).dim(), 2);
  expect_error<FileError>([&] { softhd::read_cloud(file, 3); },
                          file + ": the file holds a 2D cloud but dim=3 was requested");
  // The extension decides the format, case-insensitively: this is a text file.
  const std::string text = write("cloud.ply.txt", "1 2\n");
  EXPECT_EQ(softhd::read_cloud(text).dim(), 2);
}

// A binary vertex element of floats with extra properties of every PLY type
// under both naming schemes, and list elements before and after it.
TEST_F(CloudIo, PlyBinaryFloatWithExtraPropertiesAndFaces) {
  std::string body;
  // element face 2: list uchar int, then a double
  body += le<std::uint8_t>(3) + le<std::int32_t>(0) + le<std::int32_t>(1) + le<std::int32_t>(2);
  body += le<double>(9.0);
  body += le<std::uint8_t>(0) + le<double>(8.0);
  // element vertex 2
  const float xs[2] = {1.5f, 0.1f}, ys[2] = {-2.25f, 1e-3f}, zs[2] = {3.0f, -7.0f};
  const float vols[2] = {0.5f, 2.0f};
  for (int i = 0; i < 2; ++i) {
    body += le<std::int8_t>(-1) + le<std::uint8_t>(200) + le<std::int16_t>(-300) +
            le<std::uint16_t>(60000) + le<std::int32_t>(-7) + le<std::uint32_t>(7);
    body += le<float>(xs[i]);
    body += le<std::uint32_t>(2) + le<std::int16_t>(1) + le<std::int16_t>(2);  // list
    body += le<float>(ys[i]) + le<double>(1e300) + le<float>(zs[i]) + le<float>(vols[i]);
    body += le<std::int8_t>(1) + le<std::uint8_t>(2) + le<std::int16_t>(3) + le<std::uint16_t>(4) +
            le<std::int32_t>(5) + le<std::uint32_t>(6) + le<float>(7.0f) + le<double>(8.0);
  }
  // element edge 1: list int uchar, empty list is allowed too
  body += le<std::int32_t>(2) + le<std::uint8_t>(0) + le<std::uint8_t>(1);
  const std::string header =
      "ply\nformat binary_little_endian 1.0\ncomment binary test\n"
      "element face 2\nproperty list uchar int vertex_indices\nproperty double q\n"
      "element vertex 2\n"
      "property char a\nproperty uchar b\nproperty short c\nproperty ushort d\n"
      "property int e\nproperty uint f\n"
      "property float x\nproperty list uint int16 neighbours\nproperty float y\n"
      "property double extra\nproperty float z\nproperty float volume\n"
      "property int8 g\nproperty uint8 h\nproperty int16 i\nproperty uint16 j\n"
      "property int32 k\nproperty uint32 l\nproperty float32 m\nproperty float64 n\n"
      "element edge 1\nproperty list int uint8 ends\n"
      "end_header\n";
  const std::string file = write("b.ply", header + body);
  const PointCloud c = softhd::read_cloud(file);
  ASSERT_EQ(c.dim(), 3);
  ASSERT_EQ(c.size(), 2);
  for (int i = 0; i < 2; ++i) {
    EXPECT_EQ(c.points()(i, 0), static_cast<double>(xs[i]));
    EXPECT_EQ(c.points()(i, 1), static_cast<double>(ys[i]));
    EXPECT_EQ(c.points()(i, 2), static_cast<double>(zs[i]));
    EXPECT_EQ(c.volumes()[i], static_cast<double>(vols[i]));
  }
  // An element without properties takes no bytes, whatever its count.
  const std::string empty_element = "element nothing 18446744073709551615\n";
  const std::string with_empty = header.substr(0, header.find("element vertex")) + empty_element +
                                 header.substr(header.find("element vertex"));
  EXPECT_EQ(softhd::read_cloud(write("b3.ply", with_empty + body)).size(), 2);
  // A trailing line break after the last element is tolerated in binary files ...
  EXPECT_EQ(softhd::read_cloud(write("b2.ply", header + body + "\n")).size(), 2);
  // ... but a third vertex under "element vertex 2" is refused, not dropped.
  const std::string third = body.substr(0, body.size() / 2 - 1);
  expect_error<FileError>([&] { softhd::read_cloud(write("b4.ply", header + body + third)); },
                          "bytes of data after the last element");
}

TEST_F(CloudIo, PlyBinaryIntegerCoordinates2D) {
  const std::string header =
      "ply\nformat binary_little_endian 1.0\nelement vertex 2\n"
      "property short x\nproperty uint8 y\nend_header\n";
  const std::string body =
      le<std::int16_t>(-5) + le<std::uint8_t>(250) + le<std::int16_t>(7) + le<std::uint8_t>(1);
  const PointCloud c = softhd::read_cloud(write("i.ply", header + body));
  ASSERT_EQ(c.dim(), 2);
  Eigen::MatrixXd p(2, 2);
  p << -5, 250, 7, 1;
  EXPECT_EQ(c.points(), p);
  EXPECT_EQ(c.volumes(), Eigen::VectorXd::Ones(2));
}

TEST_F(CloudIo, PlyRoundTripIsBitExact) {
  for (int dim : {2, 3}) {
    for (bool binary : {true, false}) {
      SCOPED_TRACE("dim " + std::to_string(dim) + (binary ? " binary" : " ascii"));
      const PointCloud c = awkward_cloud(dim, 100 + dim);
      const std::string file = path(std::string("rt") + (binary ? "b" : "a") + ".ply");
      softhd::write_ply_cloud(file, c, binary);
      expect_bit_equal(softhd::read_cloud(file), c);
      expect_bit_equal(softhd::read_ply_cloud(file), c);
    }
  }
}

TEST_F(CloudIo, PlyWriterHeader) {
  const std::string file = path("hdr.ply");
  softhd::write_ply_cloud(file, PointCloud(Eigen::MatrixXd::Zero(3, 2)), false);
  std::ifstream in(file);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(text,
            "ply\nformat ascii 1.0\ncomment written by softhd\nelement vertex 3\n"
            "property double x\nproperty double y\nproperty double volume\nend_header\n"
            "0 0 1\n0 0 1\n0 0 1\n");
}

TEST_F(CloudIo, PlyErrors) {
  const std::string xyz =
      "element vertex 2\nproperty float x\nproperty float y\n"
      "property float z\nend_header\n";
  const std::string ascii = "ply\nformat ascii 1.0\n";
  const std::string binary = "ply\nformat binary_little_endian 1.0\n";
  const std::string two_points =
      le<float>(1) + le<float>(2) + le<float>(3) + le<float>(4) + le<float>(5) + le<float>(6);
  struct Case {
    std::string content;
    std::string message;  // after "<path>"
  };
  const Case cases[] = {
      {"", ": empty file (expected 'ply')"},
      {"PLY\n", ":1: not a PLY file (the first line must be 'ply')"},
      {"x y z\n1 2 3\n", ":1: not a PLY file"},
      {"ply\nformat binary_big_endian 1.0\n" + xyz,
       ":2: big-endian binary PLY is not supported (use ascii or binary_little_endian)"},
      {"ply\nformat ascii 2.0\n" + xyz, ":2: unsupported PLY version '2.0' (expected 1.0)"},
      {"ply\nformat text 1.0\n" + xyz, ":2: unknown PLY format 'text'"},
      {"ply\n" + xyz + "1 2 3\n4 5 6\n", ": the header has no 'format' line"},
      {ascii + "element vertex 1\nproperty float x\nproperty float y\n", ": missing 'end_header'"},
      {ascii + "element vertex 1\nproperty float x\nproperty float z\nend_header\n1 2\n",
       ": the vertex element needs properties x and y"},
      {ascii + "element vertex 1\nproperty float y\nproperty float z\nend_header\n1 2\n",
       ": the vertex element needs properties x and y"},
      {ascii + "element face 1\nproperty list uchar int v\nend_header\n0\n",
       ": no 'vertex' element"},
      {ascii + "element vertex 1\nproperty float16 x\n", ":4: unknown property type 'float16'"},
      {ascii + "element vertex 1\nproperty list float int x\n",
       ":4: list count type must be an integer type, got 'float'"},
      {ascii + "element vertex 1\nproperty list uchar float x\nproperty float y\n",
       ":4: vertex property 'x' must not be a list"},
      {ascii + "element vertex 1\nproperty float x\nproperty double x\n",
       ":5: duplicate vertex property 'x'"},
      {ascii + "property float x\n", ":3: 'property' before any 'element'"},
      {ascii + "element vertex -1\n", ":3: invalid element count '-1'"},
      {ascii + "element vertex 1\nelement vertex 1\n", ":4: a second 'vertex' element"},
      {ascii + "element vertex 1\nproperty\n", ":4: expected 'property <type> <name>'"},
      {ascii + "vertex 1\n", ":3: unexpected header line starting with 'vertex'"},
      {ascii + "element vertex 0\nproperty float x\nproperty float y\nend_header\n",
       ": no points in the file"},
      // ascii body
      {ascii + xyz + "1 2 3\n4 5\n",
       ":9: unexpected end of file in element 'vertex' (item 1 of 2)"},
      {ascii + xyz + "1 2 3\n4 five 6\n", ":9: expected a number, got 'five'"},
      {ascii + xyz + "1 2 3\n4 nan 6\n", ":9: non-finite coordinate, got 'nan'"},
      {ascii + xyz + "1 2 3\n4 5 6\n7\n", ":10: unexpected data after the last element: '7'"},
      {ascii + "element vertex 1\nproperty float x\nproperty float y\nproperty float volume\n"
               "end_header\n\n1 2 0\n",
       ":9: volume must be > 0, got '0'"},
      {ascii + "element face 1\nproperty list uchar int v\n" + xyz + "3 1 2\n",
       ":10: unexpected end of file in element 'face' (item 0 of 1)"},
      {ascii + "element face 1\nproperty list uchar int v\n" + xyz + "1.5 1 2\n",
       ":10: invalid list length '1.5'"},
      {ascii + "element face 1\nproperty list uchar int v\n" + xyz + "-1\n",
       ":10: invalid list length '-1'"},
      // binary body
      {binary + xyz + two_points.substr(0, 20),
       ": truncated binary data in element 'vertex' (item 1 of 2)"},
      {binary + xyz, ": truncated binary data in element 'vertex' (item 0 of 2)"},
      {binary +
           "element vertex 1000000000000\nproperty double x\nproperty double y\n"
           "end_header\n" +
           two_points,
       ": truncated binary data in element 'vertex' (item 1 of 1000000000000)"},
      {binary + "element face 1\nproperty list uchar int v\n" + xyz + le<std::uint8_t>(3) +
           le<std::int32_t>(0),
       ": truncated binary data in element 'face' (item 0 of 1)"},
      {binary + "element face 1\nproperty list char int v\n" + xyz + le<std::int8_t>(-2),
       ": negative list length in element 'face'"},
      {binary + xyz + two_points.substr(0, 16) + le<float>(NAN) + two_points.substr(20),
       ": vertex 1: non-finite coordinate (y)"},
      {binary +
           "element vertex 1\nproperty double x\nproperty double y\nproperty double volume\n"
           "end_header\n" +
           le<double>(1) + le<double>(2) + le<double>(-1),
       ": vertex 0: volume must be > 0 (volume)"},
  };
  int i = 0;
  for (const Case& c : cases) {
    const std::string file = write("bad" + std::to_string(i++) + ".ply", c.content);
    SCOPED_TRACE(c.message);
    expect_error<FileError>([&] { softhd::read_cloud(file); }, file + c.message);
  }
  // The binary variants must also work with a binary that is otherwise valid.
  EXPECT_EQ(softhd::read_cloud(write("ok.ply", binary + xyz + two_points)).size(), 2);
  EXPECT_EQ(softhd::read_cloud(write("ok2.ply", ascii + xyz + "1 2 3\n4 5 6\n")).size(), 2);
  EXPECT_EQ(softhd::read_cloud(write("ok3.ply", ascii + "element nothing 18446744073709551615\n" +
                                                    xyz + "1 2 3\n4 5 6\n"))
                .size(),
            2);
}

// 10^6 points through text and binary PLY: checks the readers scale (timings are printed).
TEST_F(CloudIo, LargeFiles) {
  const Eigen::Index n = 1000000;
  std::mt19937_64 rng(5);
  Eigen::MatrixXd p(n, 3);
  for (Eigen::Index i = 0; i < p.size(); ++i) {
    p.data()[i] = static_cast<double>(rng() >> 11) * 0x1.0p-53;
  }
  const PointCloud c(p, Eigen::VectorXd::Constant(n, 1e-6));
  for (const char* name : {"big.txt", "big.ply"}) {
    const std::string file = path(name);
    const auto t0 = std::chrono::steady_clock::now();
    if (std::string(name) == "big.txt") {
      softhd::write_text_cloud(file, c);
    } else {
      softhd::write_ply_cloud(file, c);
    }
    const auto t1 = std::chrono::steady_clock::now();
    const PointCloud back = softhd::read_cloud(file);
    const auto t2 = std::chrono::steady_clock::now();
    expect_bit_equal(back, c);
    std::printf("[ timing   ] %s: write %.3f s, read %.3f s\n", name,
                std::chrono::duration<double>(t1 - t0).count(),
                std::chrono::duration<double>(t2 - t1).count());
  }
}

// Issue 29 item 7: a write that fails part way (here a file-size limit, as a full disk)
// throws FileError naming the file, leaves the earlier file intact and no temporary behind.
TEST(AtomicFile, AFailedWriteKeepsTheOldFileAndLeavesNoTemporary) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::path(::testing::TempDir()) / "softhd_atomic";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string path = (dir / "out.txt").string();
  softhd::write_file_atomically(path, "old\n");
  struct sigaction ignore {
  }, old_action{};
  ignore.sa_handler = SIG_IGN;
  sigaction(SIGXFSZ, &ignore, &old_action);  // writes past the limit then fail with EFBIG
  rlimit old_limit{};
  getrlimit(RLIMIT_FSIZE, &old_limit);
  rlimit small = old_limit;
  small.rlim_cur = 1000;
  setrlimit(RLIMIT_FSIZE, &small);
  bool threw = false;
  try {
    softhd::write_file_atomically(path, std::string(100000, 'x'));
  } catch (const softhd::FileError& e) {
    threw = true;
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
  setrlimit(RLIMIT_FSIZE, &old_limit);
  sigaction(SIGXFSZ, &old_action, nullptr);
  EXPECT_TRUE(threw);
  std::ifstream in(path);
  std::string content((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(content, "old\n");
  int files = 0;
  for (const auto& entry : fs::directory_iterator(dir)) files += entry.is_regular_file();
  EXPECT_EQ(files, 1);  // out.txt alone: the temporary was removed
}

// A device is written directly (no rename over the device node), with its errors reported.
TEST(AtomicFile, ADeviceIsWrittenDirectlyAndAFullOneIsAnError) {
  EXPECT_NO_THROW(softhd::write_file_atomically("/dev/null", "x"));
  EXPECT_THROW(softhd::write_file_atomically("/dev/full", "x"), softhd::FileError);
  EXPECT_TRUE(std::filesystem::is_character_file("/dev/full"));
}

// The Gmsh MSH reader (io/msh.hpp) on meshes made by Gmsh 4.8 (tests/data/meshes, made by
// scripts/make_test_meshes.sh) and on broken copies of them.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <fstream>
#include <iterator>
#include <map>
#include <string>

#include "expect_error.hpp"
#include "softhd/error.hpp"
#include "softhd/io/msh.hpp"

using softhd::FileError;
using softhd::io::MshElementBlock;
using softhd::io::MshFile;
using softhd::test::expect_error;

namespace {

std::string mesh_path(const std::string& name) {
  return std::string(SOFTHD_SOURCE_DIR) + "/tests/data/meshes/" + name;
}

MshFile read(const std::string& name) { return softhd::io::read_msh(mesh_path(name)); }

std::string slurp(const std::string& name) {
  std::ifstream in(mesh_path(name), std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

// `text` with its first `from` replaced by `to` (which must be there).
std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const std::size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

void expect_parse_error(const std::string& text, const std::string& needle) {
  expect_error<FileError>([&] { softhd::io::parse_msh(text, "bad.msh"); }, needle);
}

Eigen::Vector3d node(const MshFile& m, int i) { return m.nodes.row(i).transpose(); }

// Total measure of a block's elements from their corner nodes: tetrahedra (volume) or
// triangles (area).
double simplex_measure(const MshFile& m, const MshElementBlock& b) {
  double sum = 0;
  for (Eigen::Index e = 0; e < b.nodes.rows(); ++e) {
    const Eigen::Vector3d a = node(m, b.nodes(e, 0));
    const Eigen::Vector3d u = node(m, b.nodes(e, 1)) - a;
    const Eigen::Vector3d v = node(m, b.nodes(e, 2)) - a;
    sum += b.dim == 3 ? std::abs(u.cross(v).dot(node(m, b.nodes(e, 3)) - a)) / 6
                      : u.cross(v).norm() / 2;
  }
  return sum;
}

// The measure of the elements of dimension `dim` in the physical group `name`.
double group_measure(const MshFile& m, int dim, const std::string& name) {
  const auto* g = m.group(dim, name);
  EXPECT_NE(g, nullptr) << name;
  double sum = 0;
  for (const MshElementBlock& b : m.blocks) {
    if (g != nullptr && b.dim == dim && b.physical_tags.size() == 1 && b.physical_tags[0] == g->tag)
      sum += simplex_measure(m, b);
  }
  return sum;
}

// Two files hold the same mesh: nodes, tags, groups, blocks (MSH 2.2 blocks are runs of
// elements; Gmsh writes them in entity order, so they match 4.1's blocks here).
void expect_same_mesh(const MshFile& a, const MshFile& b) {
  EXPECT_EQ(a.nodes, b.nodes);
  EXPECT_EQ(a.node_tags, b.node_tags);
  ASSERT_EQ(a.physical_groups.size(), b.physical_groups.size());
  for (std::size_t i = 0; i < a.physical_groups.size(); ++i) {
    EXPECT_EQ(a.physical_groups[i].dim, b.physical_groups[i].dim);
    EXPECT_EQ(a.physical_groups[i].tag, b.physical_groups[i].tag);
    EXPECT_EQ(a.physical_groups[i].name, b.physical_groups[i].name);
  }
  ASSERT_EQ(a.blocks.size(), b.blocks.size());
  for (std::size_t i = 0; i < a.blocks.size(); ++i) {
    EXPECT_EQ(a.blocks[i].gmsh_type, b.blocks[i].gmsh_type);
    EXPECT_EQ(a.blocks[i].dim, b.blocks[i].dim);
    EXPECT_EQ(a.blocks[i].entity, b.blocks[i].entity);
    EXPECT_EQ(a.blocks[i].physical_tags, b.blocks[i].physical_tags);
    EXPECT_EQ(a.blocks[i].nodes, b.blocks[i].nodes);
    EXPECT_EQ(a.blocks[i].element_tags, b.blocks[i].element_tags);
  }
}

// The cube of cube_tet.geo: groups, volumes of body and layer, area of base.
void expect_cube(const MshFile& m, int gmsh_type, int num_nodes) {
  EXPECT_EQ(m.nodes.rows(), num_nodes);
  EXPECT_EQ(m.max_element_dim(), 3);
  ASSERT_NE(m.group(3, "body"), nullptr);
  EXPECT_EQ(m.group(3, "body")->tag, 1);
  EXPECT_EQ(m.group(3, "layer")->tag, 2);
  EXPECT_EQ(m.group(2, "base")->tag, 11);
  EXPECT_NE(m.group(2, "tip"), nullptr);
  EXPECT_EQ(m.group(3, "base"), nullptr);
  EXPECT_EQ(m.group(2, "nothing"), nullptr);
  int tets = 0;
  for (const MshElementBlock& b : m.blocks) {
    if (b.dim == 3) {
      EXPECT_EQ(b.gmsh_type, gmsh_type);
      tets += static_cast<int>(b.nodes.rows());
    }
    EXPECT_EQ(b.element_tags.size(), static_cast<std::size_t>(b.nodes.rows()));
    EXPECT_EQ(b.nodes.cols(), softhd::io::gmsh_nodes_per_element(b.gmsh_type));
    EXPECT_GE(b.nodes.minCoeff(), 0);
    EXPECT_LT(b.nodes.maxCoeff(), m.nodes.rows());
  }
  EXPECT_EQ(tets, 481);
  EXPECT_NEAR(group_measure(m, 3, "body"), 0.6, 1e-12);
  EXPECT_NEAR(group_measure(m, 3, "layer"), 0.4, 1e-12);
  EXPECT_NEAR(group_measure(m, 2, "base"), 1.0, 1e-12);
  EXPECT_NEAR(group_measure(m, 2, "tip"), 1.0, 1e-12);
}

}  // namespace

TEST(Msh, ElementTypeTables) {
  using namespace softhd::io;
  const int types[] = {kGmshPoint, kGmshLine2, kGmshLine3, kGmshTri3, kGmshTri6, kGmshQuad4,
                       kGmshQuad9, kGmshTet4,  kGmshTet10, kGmshHex8, kGmshHex27};
  const int nodes[] = {1, 2, 3, 3, 6, 4, 9, 4, 10, 8, 27};
  const int dims[] = {0, 1, 1, 2, 2, 2, 2, 3, 3, 3, 3};
  for (int i = 0; i < 11; ++i) {
    EXPECT_EQ(gmsh_nodes_per_element(types[i]), nodes[i]) << types[i];
    EXPECT_EQ(gmsh_element_dim(types[i]), dims[i]) << types[i];
  }
  for (int other : {0, 6, 7, 16, 17, 99, -1}) {
    EXPECT_EQ(gmsh_nodes_per_element(other), 0);
    EXPECT_EQ(gmsh_element_dim(other), -1);
  }
}

TEST(Msh, Tet4CubeIsTheSameInAsciiBinaryAnd22) {
  const MshFile a = read("cube_tet4_v41.msh");
  const MshFile b = read("cube_tet4_v41_bin.msh");
  const MshFile c = read("cube_tet4_v22.msh");
  EXPECT_EQ(a.version, 4.1);
  EXPECT_FALSE(a.binary);
  EXPECT_TRUE(b.binary);
  EXPECT_EQ(c.version, 2.2);
  EXPECT_EQ(a.source, mesh_path("cube_tet4_v41.msh"));
  expect_cube(a, softhd::io::kGmshTet4, 166);
  expect_same_mesh(a, b);
  expect_same_mesh(a, c);
  EXPECT_TRUE(a.notes.empty());
}

TEST(Msh, Tet10CubeIsTheSameInEveryFormatWithMidsideNodesInGmshOrder) {
  const MshFile a = read("cube_tet10_v41.msh");
  expect_cube(a, softhd::io::kGmshTet10, 956);
  expect_same_mesh(a, read("cube_tet10_v41_bin.msh"));
  expect_same_mesh(a, read("cube_tet10_v22.msh"));
  // Straight edges (a box): Gmsh's edges 4:(0,1) 5:(1,2) 6:(2,0) 7:(3,0) 8:(3,2) 9:(3,1).
  const int edges[6][2] = {{0, 1}, {1, 2}, {2, 0}, {3, 0}, {3, 2}, {3, 1}};
  for (const MshElementBlock& b : a.blocks) {
    if (b.dim != 3) continue;
    for (Eigen::Index e = 0; e < b.nodes.rows(); ++e) {
      for (int k = 0; k < 6; ++k) {
        const Eigen::Vector3d mid =
            (node(a, b.nodes(e, edges[k][0])) + node(a, b.nodes(e, edges[k][1]))) / 2;
        ASSERT_LT((node(a, b.nodes(e, 4 + k)) - mid).norm(), 1e-12) << e << " " << k;
      }
    }
  }
}

TEST(Msh, Hex27TransfiniteBox) {
  const MshFile m = read("box_hex27_v41.msh");
  EXPECT_EQ(m.nodes.rows(), 9 * 5 * 5);
  ASSERT_EQ(m.blocks.size(), 2u);
  const MshElementBlock& hex = m.blocks[1];
  EXPECT_EQ(hex.gmsh_type, softhd::io::kGmshHex27);
  EXPECT_EQ(hex.nodes.rows(), 16);
  EXPECT_EQ(hex.physical_tags, std::vector<int>{m.group(3, "body")->tag});
  EXPECT_EQ(m.blocks[0].gmsh_type, softhd::io::kGmshQuad9);
  EXPECT_EQ(m.blocks[0].physical_tags, std::vector<int>{m.group(2, "x0")->tag});
  // node 26 is the centre: the mean of the 8 corners; the corners span 0.5 x 0.5 x 0.5
  for (Eigen::Index e = 0; e < hex.nodes.rows(); ++e) {
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    Eigen::Vector3d lo = node(m, hex.nodes(e, 0)), hi = lo;
    for (int k = 0; k < 8; ++k) {
      mean += node(m, hex.nodes(e, k)) / 8;
      lo = lo.cwiseMin(node(m, hex.nodes(e, k)));
      hi = hi.cwiseMax(node(m, hex.nodes(e, k)));
    }
    EXPECT_LT((node(m, hex.nodes(e, 26)) - mean).norm(), 1e-11);
    EXPECT_LT((hi - lo - Eigen::Vector3d(0.5, 0.5, 0.5)).norm(), 1e-11);
  }
}

TEST(Msh, PlaneMeshOfTri6Quad9AndLine3) {
  const MshFile m = read("plate_2d_v41.msh");
  expect_same_mesh(m, read("plate_2d_v22.msh"));
  EXPECT_EQ(m.max_element_dim(), 2);
  EXPECT_EQ(m.nodes.rows(), 132);
  EXPECT_EQ(m.nodes.col(2).cwiseAbs().maxCoeff(), 0.0);
  ASSERT_EQ(m.blocks.size(), 3u);
  EXPECT_EQ(m.blocks[0].gmsh_type, softhd::io::kGmshLine3);
  EXPECT_EQ(m.blocks[1].gmsh_type, softhd::io::kGmshTri6);
  EXPECT_EQ(m.blocks[2].gmsh_type, softhd::io::kGmshQuad9);
  EXPECT_EQ(m.blocks[2].nodes.rows(), 4);
  EXPECT_NEAR(group_measure(m, 2, "tris"), 1.0, 1e-12);
  ASSERT_NE(m.group(1, "left"), nullptr);
  EXPECT_EQ(m.blocks[0].physical_tags, std::vector<int>{m.group(1, "left")->tag});
}

TEST(Msh, SparseNodeTagsAreCompactedInIncreasingOrder) {
  const MshFile m = read("sparse.msh");
  EXPECT_EQ(m.nodes.rows(), 439);
  EXPECT_EQ(m.node_tags.back(), 463);
  for (std::size_t i = 1; i < m.node_tags.size(); ++i)
    EXPECT_LT(m.node_tags[i - 1], m.node_tags[i]);
  EXPECT_NEAR(group_measure(m, 3, "left"), 1.0, 1e-12);
  EXPECT_NEAR(group_measure(m, 3, "right"), 1.0, 1e-12);
}

TEST(Msh, NodeAndElementDataBlocks) {
  const MshFile m = read("fields.msh");
  EXPECT_EQ(m.node_tags, (std::vector<std::int64_t>{1, 2, 3, 5, 9}));
  ASSERT_EQ(m.blocks.size(), 1u);
  EXPECT_EQ(m.blocks[0].nodes.row(1), Eigen::RowVector4i(1, 2, 3, 4));
  ASSERT_EQ(m.data.size(), 2u);
  const softhd::io::MshDataBlock& f = m.data[0];
  EXPECT_EQ(f.name, "fibres");
  EXPECT_FALSE(f.per_element);
  EXPECT_EQ(f.components, 3);
  EXPECT_EQ(f.tags, (std::vector<std::int64_t>{0, 1, 2, 3, 4}));
  EXPECT_EQ(f.values.row(4), Eigen::RowVector3d(0.6, 0.8, 0));
  const softhd::io::MshDataBlock& s = m.data[1];
  EXPECT_EQ(s.name, "stiffness");
  EXPECT_TRUE(s.per_element);
  EXPECT_EQ(s.tags, (std::vector<std::int64_t>{20, 10}));
  EXPECT_EQ(s.values, Eigen::Vector2d(2.5, 1.5));
  ASSERT_EQ(m.notes.size(), 1u);
  EXPECT_EQ(m.notes[0], "skipped section $ElementNodeData");
  // the same mesh and node data, written by Gmsh in binary
  const MshFile b = read("fields_bin.msh");
  EXPECT_TRUE(b.binary);
  expect_same_mesh(m, b);
  ASSERT_EQ(b.data.size(), 1u);
  EXPECT_EQ(b.data[0].name, "fibres");
  EXPECT_EQ(b.data[0].tags, f.tags);
  EXPECT_EQ(b.data[0].values, f.values);
}

TEST(Msh, LowerDimensionalTypesAreSkippedWithANoteTopDimensionalOnesRefused) {
  const std::string all = slurp("fields.msh");
  const std::string text = all.substr(0, all.find("$NodeData"));  // the mesh alone
  // a block of 8-node quadrangles (type 16) on a surface: skipped
  const std::string with_quad8 = replaced(replaced(text, "1 2 1 2\n", "2 3 1 20\n"), "$EndElements",
                                          "2 1 16 1\n30 1 2 3 5 9 1 2 3\n$EndElements");
  const MshFile m = softhd::io::parse_msh(with_quad8, "quad8.msh");
  EXPECT_EQ(m.blocks.size(), 1u);
  ASSERT_FALSE(m.notes.empty());
  EXPECT_EQ(m.notes.back(), "skipped 1 elements of Gmsh type 16 (dimension 2)");
  // prisms (type 6) and an unknown type in a volume block: refused
  expect_parse_error(replaced(text, "3 1 4 2\n", "3 1 6 2\n"),
                     "bad.msh:28: element type 6 of the mesh's top dimension 3 is not read");
  expect_parse_error(replaced(text, "3 1 4 2\n", "3 1 99 2\n"), "bad.msh:28: element type 99");
  // MSH 2.2: an unknown type
  const std::string v22 = slurp("cube_tet4_v22.msh");
  const std::size_t at = v22.find("$Elements\n") + 10;
  const std::size_t line2 = v22.find('\n', at) + 1;  // the first element's line
  std::string bad = v22;
  const std::size_t type_at = bad.find(' ', line2) + 1;
  bad.replace(type_at, 1, "77");
  const auto line = std::count(v22.begin(), v22.begin() + static_cast<long>(line2), '\n') + 1;
  expect_parse_error(bad, "bad.msh:" + std::to_string(line) + ": unknown element type 77");
}

TEST(Msh, BadInputIsOneLineNamingTheFileAndLine) {
  const std::string text = slurp("fields.msh");
  // a node tag referenced but not defined
  expect_parse_error(replaced(text, "20 2 3 5 9", "20 2 3 5 8"),
                     "bad.msh:30: node tag 8 is not defined in $Nodes");
  expect_parse_error(replaced(text, "1 1 2\n", "1 nan 2\n"), "bad.msh:24: non-finite coordinate");
  expect_parse_error(replaced(text, "1 1 2\n", "1 inf 2\n"), "bad.msh:24: non-finite coordinate");
  expect_parse_error(replaced(text, "1 5 1 9", "1 99999999999999 1 9"),
                     "bad.msh:13: the number of nodes 99999999999999 exceeds what the");
  expect_parse_error(replaced(text, "1 5 1 9", "1 -5 1 9"),
                     "bad.msh:13: the number of nodes -5 is negative");
  expect_parse_error(replaced(text, "\n9\n0 0 0", "\n1\n0 0 0"),
                     "bad.msh:12: node tag 1 is defined twice");
  expect_parse_error(replaced(text, "\n9\n0 0 0", "\n0\n0 0 0"),
                     "bad.msh:19: a node tag 0 is out of range");
  expect_parse_error(replaced(text, "3 1 0 5", "3 1 0 4"),
                     "bad.msh:23: the node blocks hold 4 nodes, the section declares 5");
  expect_parse_error(replaced(text, "$EndNodes", "$EndNode"),
                     "bad.msh:25: expected $EndNodes, got '$EndNode'");
  expect_parse_error(replaced(text, "1 0 0 0 1 1 2", "1 0 0 0 1 1 x"),
                     "bad.msh:10: expected a bounding box coordinate");
  expect_parse_error(replaced(text, "3 1 \"body\"", "3 1 \"body"),
                     "bad.msh:6: a physical group's name has no closing quote");
  expect_parse_error(replaced(text, "4.1 0 8", "4.0 0 8"),
                     "bad.msh:2: MSH version '4.0' is not read");
  expect_parse_error(replaced(text, "4.1 0 8", "4.1 0 4"), "bad.msh:2: data size 4 is not 8");
  expect_parse_error(replaced(text, "9 0.6 0.8 0", "7 0.6 0.8 0"), "node tag 7 is not defined");
  expect_parse_error(replaced(text, "20 2.5", "21 2.5"),
                     "element tag 21 is not defined in $Elements");
  expect_parse_error(replaced(text, "$EndElementNodeData", ""), "no $EndElementNodeData");
  expect_parse_error("", "bad.msh:1: not a Gmsh mesh file");
  expect_parse_error("solid cube\n", "bad.msh:1: not a Gmsh mesh file");
  expect_parse_error(text.substr(0, text.find("$Elements")), "no $Elements section");
  // truncated: every cut of the file is refused with one line (or still parses, at the end)
  for (std::size_t cut = 0; cut < text.find("$EndElements") + 4; ++cut) {
    try {
      softhd::io::parse_msh(text.substr(0, cut), "cut.msh");
      ADD_FAILURE() << "a cut at " << cut << " parsed";
    } catch (const FileError& e) {
      const std::string what = e.what();
      EXPECT_EQ(what.rfind("cut.msh:", 0), 0u) << what;
      EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    }
  }
}

TEST(Msh, TruncatedBinaryNamesTheSectionAndByte) {
  const std::string bin = slurp("cube_tet4_v41_bin.msh");
  const std::size_t nodes = bin.find("$Nodes\n") + 7;
  expect_parse_error(bin.substr(0, nodes + 100), "bad.msh: $Nodes at byte ");
  expect_parse_error(bin.substr(0, nodes + 4),
                     "bad.msh: $Nodes at byte " + std::to_string(nodes) +
                         ": truncated: the number of node blocks needs 8 bytes, 4 left");
  const std::size_t elements = bin.find("$Elements\n") + 10;
  expect_parse_error(bin.substr(0, elements + 50), "bad.msh: $Elements at byte ");
  // a huge count of node blocks
  std::string huge = bin;
  huge.replace(nodes, 8, std::string("\xff\xff\xff\xff\xff\xff\xff\x0f", 8));
  expect_parse_error(huge, "bad.msh: $Nodes at byte " + std::to_string(nodes) +
                               ": the number of node blocks 1152921504606846975 exceeds");
  // a NaN coordinate in the first node block (after its 20-byte header and one tag)
  std::string nan = bin;
  const std::size_t first_block = nodes + 32;
  const std::size_t coordinate = first_block + 20 + 8;
  const double q = std::nan("");
  nan.replace(coordinate, 8, std::string(reinterpret_cast<const char*>(&q), 8));
  expect_parse_error(
      nan, "bad.msh: $Nodes at byte " + std::to_string(coordinate) + ": non-finite coordinate");
  // every cut refused with one line naming the file
  for (std::size_t cut = 0; cut < bin.rfind("$EndElements") + 4; cut += 97) {
    try {
      softhd::io::parse_msh(bin.substr(0, cut), "cut.msh");
      ADD_FAILURE() << "a cut at " << cut << " parsed";
    } catch (const FileError& e) {
      EXPECT_EQ(std::string(e.what()).rfind("cut.msh", 0), 0u) << e.what();
    }
  }
}

TEST(Msh, MissingFileIsAFileError) {
  expect_error<FileError>([] { softhd::io::read_msh(mesh_path("no_such.msh")); }, "cannot open '");
}

// A byte order mark (some editors write one) is skipped; a file that is not a mesh file is
// refused on its first bytes: a device (/dev/zero was read until memory ran out), a folder,
// a point cloud.
TEST(Msh, ByteOrderMarkDevicesAndOtherFiles) {
  const std::string text = slurp("fields.msh");
  const MshFile plain = softhd::io::parse_msh(text, "a.msh");
  const MshFile marked = softhd::io::parse_msh("\xEF\xBB\xBF" + text, "b.msh");
  expect_same_mesh(plain, marked);
  expect_parse_error("\xEF\xBB\xBF", "bad.msh:1: not a Gmsh mesh file");
  expect_error<FileError>([] { softhd::io::read_msh("/dev/zero"); },
                          "'/dev/zero' is not a regular file");
  expect_error<FileError>([] { softhd::io::read_msh(::testing::TempDir()); },
                          "is not a regular file");
  const std::string cloud = ::testing::TempDir() + "/cloud.msh";
  {
    std::ofstream out(cloud);
    out << "\n# a point cloud\n";
    for (int i = 0; i < 20000; ++i) out << i << " 0.5 0.25\n";
  }
  expect_error<FileError>([&] { softhd::io::read_msh(cloud); },
                          cloud + ":2: not a Gmsh mesh file (it does not start with $MeshFormat)");
}

// Two data blocks of one name: the field a scene names would be the last one, silently.
TEST(Msh, ADataBlockNameIsGivenOnce) {
  const std::string text = slurp("fields.msh");
  expect_parse_error(replaced(text, "\"stiffness\"", "\"fibres\""),
                     "bad.msh:47: a second data block named 'fibres'");
}

// The counts of scan_msh_counts are those of the parse (nodes, and elements per type), in
// every encoding; the counts check of read_msh runs before the parse.
TEST(Msh, ScannedCountsAreTheParsedOnes) {
  for (const char* name : {"cube_tet4_v41.msh", "cube_tet4_v41_bin.msh", "cube_tet4_v22.msh",
                           "cube_tet10_v41.msh", "cube_tet10_v41_bin.msh", "cube_tet10_v22.msh",
                           "box_hex27_v41.msh", "plate_2d_v22.msh", "fields.msh", "sparse.msh"}) {
    const MshFile m = read(name);
    std::map<int, std::size_t> per_type;
    for (const MshElementBlock& b : m.blocks)
      per_type[b.gmsh_type] += static_cast<std::size_t>(b.nodes.rows());
    softhd::io::MshCounts c;
    ASSERT_TRUE(softhd::io::scan_msh_counts(slurp(name), &c)) << name;
    EXPECT_EQ(c.nodes, static_cast<std::size_t>(m.nodes.rows())) << name;
    for (auto& [type, n] : c.elements) {  // the kept types (skipped ones are counted too)
      if (softhd::io::gmsh_nodes_per_element(type) > 0) {
        EXPECT_EQ(n, per_type[type]) << name;
      }
    }
    for (auto& [type, n] : per_type) EXPECT_EQ(c.elements[type], n) << name << type;
  }
  softhd::io::MshCounts c;
  EXPECT_FALSE(softhd::io::scan_msh_counts("solid cube\n", &c));
  const std::string text = slurp("cube_tet4_v41.msh");
  EXPECT_FALSE(softhd::io::scan_msh_counts(text.substr(0, text.find("$Elements") + 12), &c));
  bool called = false;
  expect_error<FileError>(
      [&] {
        softhd::io::read_msh(mesh_path("cube_tet4_v41.msh"), [&](const softhd::io::MshCounts& k) {
          called = true;
          EXPECT_EQ(k.nodes, 166u);  // the file's $Nodes header
          throw FileError("refused");
        });
      },
      "refused");
  EXPECT_TRUE(called);
}

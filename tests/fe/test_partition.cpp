// The partition of the PETSc state backend (lib/src/fe/petsc/partition.hpp), on one process:
// every rank's part built here, for boxes (2D and 3D) and Gmsh meshes (tetrahedra and
// hexahedra) and 1-5 ranks. Checked against brute force over all parts: each element
// in exactly one part, each shared node owned by the lowest rank touching it, the rows one
// contiguous range per rank with the same row for a dof on every rank that has it, and the
// preallocation counts equal to the serial assembler's sparsity pattern (built by other
// code: Assembler's element-to-nonzero pattern on the whole mesh).

#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "fe/petsc/partition.hpp"
#include "softhd/control/scene.hpp"
#include "softhd/error.hpp"
#include "softhd/fe/assembly.hpp"

namespace softhd::fe::petsc_detail {
namespace {

std::string source(const std::string& path) { return std::string(SOFTHD_SOURCE_DIR) + "/" + path; }

// A scene on a mesh file of tests/data/meshes, clamped on `clamp`, one material; order 0:
// the file's.
Scene file_scene(const std::string& mesh, const std::string& clamp, int order) {
  const std::string text = R"({"mesh": {"type": "gmsh", "file": ")" +
                           source("tests/data/meshes/" + mesh) + R"(")" +
                           (order ? ", \"order\": " + std::to_string(order) : "") + R"(},
    "material": {"model": "mooney_rivlin", "a": 1, "b": 0.2, "c": 3},
    "fibers": [1, 0, 0], "clamp": [")" +
                           clamp + R"("],
    "control": {"space": "vertex", "lower": -1, "upper": 0}})";
  return parse_scene(text, ::testing::TempDir() + "/partition.json");
}

// A box scene; `constraints` are extra JSON constraints (partly fixed nodes).
Scene box_scene(const std::string& cells, int order, const std::string& constraints = "") {
  const bool two_d = std::count(cells.begin(), cells.end(), ',') == 1;
  const std::string text = std::string(R"({"mesh": {"type": "box", "lower": )") +
                           (two_d ? "[0, 0]" : "[0, 0, 0]") + R"(, "upper": )" +
                           (two_d ? "[4, 1]" : "[4, 1, 0.5]") + R"(, "cells": [)" + cells +
                           R"(], "order": )" + std::to_string(order) + R"(},
    "material": {"model": "mooney_rivlin", "a": 1, "b": 0.2, "c": 3},
    "fibers": [1, 0, 0], "clamp": ["x0"], )" +
                           (constraints.empty() ? "" : R"("constraints": )" + constraints + ", ") +
                           R"("control": {"space": "element", "lower": -1, "upper": 0}})";
  return parse_scene(text, "box.json");
}

// All parts of the scene's body among `size` ranks, checked against the whole mesh.
void check_partition(const Scene& scene, int size) {
  SCOPED_TRACE(scene.name + " on " + std::to_string(size) + " ranks");
  const Assembler whole = scene.body.make_assembler();  // kFull: the serial sparsity pattern
  const Mesh& g = whole.mesh();
  const int dim = g.dim;
  std::vector<Partition> parts;
  for (int r = 0; r < size; ++r) parts.push_back(make_partition(scene.body, r, size));

  // Each element in exactly one part, parts balanced; nodes, regions and fibres copied.
  std::vector<int> element_rank(g.num_elements(), -1), lowest(g.num_nodes(), size);
  for (const Partition& p : parts) {
    EXPECT_GE(static_cast<Eigen::Index>(p.global_element.size()), 1);
    EXPECT_FALSE(p.mesh.structured());
    for (size_t k = 0; k < p.global_element.size(); ++k) {
      const int e = p.global_element[k];
      ASSERT_EQ(element_rank[e], -1) << "element " << e << " in two parts";
      element_rank[e] = p.rank;
      EXPECT_EQ(p.mesh.element_region[k], g.element_region[e]);
      for (int a = 0; a < g.nodes_per_element(); ++a) {
        const int n = p.global_node[p.mesh.elements(k, a)];
        ASSERT_EQ(n, g.elements(e, a));
        EXPECT_EQ(p.mesh.nodes.row(p.mesh.elements(k, a)), g.nodes.row(n));
        lowest[n] = std::min(lowest[n], p.rank);
      }
      for (int a = 0; a < g.element_vertices.cols(); ++a)
        EXPECT_EQ(p.global_vertex[p.mesh.element_vertices(k, a)], g.element_vertices(e, a));
    }
    EXPECT_EQ(p.fibers.values.cols(), 1);
  }
  EXPECT_EQ(std::count(element_rank.begin(), element_rank.end(), -1), 0);

  // Rows: contiguous ranges in rank order; every free dof owned once, by the lowest rank
  // touching its node; the same row on every rank that has it.
  std::map<std::int64_t, std::int64_t> row_of_dof;  // global dof -> row
  std::map<std::int64_t, int> owner_of_dof;
  std::int64_t next = 0;
  for (const Partition& p : parts) {
    const FreeNumbering& f = p.numbering;
    EXPECT_EQ(f.owned_begin, next);
    next = f.owned_end;
    ASSERT_EQ(static_cast<std::int64_t>(f.owned_local.size()), f.owned_end - f.owned_begin);
    for (size_t i = 0; i < f.owned_local.size(); ++i) {
      const std::int64_t dof = f.owned_global_dof[i];
      EXPECT_EQ(f.local_to_global[f.owned_local[i]], f.owned_begin + static_cast<std::int64_t>(i));
      EXPECT_TRUE(owner_of_dof.emplace(dof, p.rank).second) << "dof " << dof << " owned twice";
      EXPECT_EQ(p.rank, lowest[dof / dim]) << "node " << dof / dim;
    }
    const DofMap local = make_dof_map(p.mesh, scene.body.constraints);
    for (Eigen::Index fi = 0; fi < local.num_free; ++fi) {
      const int dof = local.free_dofs[fi];
      const std::int64_t global = std::int64_t{p.global_node[dof / dim]} * dim + dof % dim;
      const auto [it, fresh] = row_of_dof.emplace(global, f.local_to_global[fi]);
      if (!fresh) {
        EXPECT_EQ(it->second, f.local_to_global[fi]) << "dof " << global;
      }
    }
  }
  EXPECT_EQ(next, whole.dofs().num_free);
  EXPECT_EQ(static_cast<Eigen::Index>(owner_of_dof.size()), whole.dofs().num_free);
  EXPECT_EQ(static_cast<Eigen::Index>(row_of_dof.size()), whole.dofs().num_free);
  for (const Partition& p : parts) EXPECT_EQ(p.numbering.num_global, whole.dofs().num_free);

  // Preallocation: per row, the serial pattern's nonzeros (both triangles) split by owner.
  std::map<std::int64_t, std::pair<int, int>> counts;  // global dof -> (diagonal, off)
  const SparseMatrix K = whole.tangent_pattern();
  auto add = [&](std::int64_t row_dof, std::int64_t col_dof) {
    auto& c = counts[row_dof];
    ++(owner_of_dof[row_dof] == owner_of_dof[col_dof] ? c.first : c.second);
  };
  for (int j = 0; j < K.outerSize(); ++j)
    for (SparseMatrix::InnerIterator it(K, j); it; ++it) {
      const std::int64_t I = whole.dofs().free_dofs[it.row()], J = whole.dofs().free_dofs[j];
      add(I, J);
      if (I != J) add(J, I);
    }
  for (const Partition& p : parts)
    for (size_t i = 0; i < p.numbering.owned_global_dof.size(); ++i) {
      const auto& c = counts[p.numbering.owned_global_dof[i]];
      EXPECT_EQ(p.numbering.diagonal_nonzeros[i], c.first);
      EXPECT_EQ(p.numbering.off_diagonal_nonzeros[i], c.second);
    }
}

TEST(Partition, BoxesQ1Q2In2DAnd3D) {
  for (int size = 1; size <= 5; ++size) {
    check_partition(box_scene("8, 2, 2", 2), size);
    check_partition(box_scene("7, 3", 1), size);
    // Partly constrained nodes (block size 1).
    check_partition(box_scene("5, 3, 2", 1, R"([{"face": "z0", "components": [2]}])"), size);
  }
}

TEST(Partition, GmshMeshes) {
  for (int size = 1; size <= 5; ++size) {
    check_partition(file_scene("cube_tet4_v41.msh", "base", 1), size);
    check_partition(file_scene("cube_tet4_v41.msh", "base", 2), size);   // straight P2
    check_partition(file_scene("cube_tet10_v41.msh", "base", 0), size);  // the file's P2
    check_partition(file_scene("box_hex27_v41.msh", "x0", 0), size);     // Q2 from Gmsh
  }
}

// On 2 ranks a box is cut into two slabs between cell planes along its axis with the most
// cells (⌊nc/2⌋ and ⌈nc/2⌉ cells), rows numbered plane by plane along it; an unstructured
// body into parts of ⌊E/2⌋ and ⌈E/2⌉ elements.
TEST(Partition, TwoRanksCutSlabsOfBoxes) {
  const Scene s = box_scene("3, 7, 2", 2);  // most cells along y: the cut is y = 3/7
  const Mesh g = s.body.make_mesh();
  const Partition p0 = make_partition(s.body, 0, 2), p1 = make_partition(s.body, 1, 2);
  EXPECT_EQ(p0.axis, 1);
  EXPECT_EQ(p0.global_element.size(), 3u * 3 * 2);
  for (int e : p0.global_element)
    for (int a = 0; a < g.nodes_per_element(); ++a)
      EXPECT_LE(g.nodes(g.elements(e, a), 1), 3.0 / 7.0 + 1e-12);
  for (int e : p1.global_element)
    for (int a = 0; a < g.nodes_per_element(); ++a)
      EXPECT_GE(g.nodes(g.elements(e, a), 1), 3.0 / 7.0 - 1e-12);
  // Rows plane by plane: y never decreases along the rows of either rank.
  for (const Partition* p : {&p0, &p1}) {
    const std::vector<std::int64_t>& dofs = p->numbering.owned_global_dof;
    for (size_t i = 1; i < dofs.size(); ++i)
      EXPECT_LE(g.nodes(dofs[i - 1] / 3, 1), g.nodes(dofs[i] / 3, 1));
  }
  const Scene cube = file_scene("cube_tet4_v41.msh", "base", 1);
  const Eigen::Index E = cube.body.file_mesh->num_elements();
  EXPECT_EQ(static_cast<Eigen::Index>(make_partition(cube.body, 0, 2).global_element.size()),
            E / 2);
}

TEST(Partition, RefusesMoreRanksThanElements) {
  const Scene s = box_scene("2, 1, 1", 1);
  EXPECT_NO_THROW(make_partition(s.body, 1, 2));
  EXPECT_THROW(make_partition(s.body, 0, 3), InvalidArgument);
}

}  // namespace
}  // namespace softhd::fe::petsc_detail

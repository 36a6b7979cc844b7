#pragma once
/// \file msh.hpp
/// Gmsh mesh files, read by the project itself (MSH 4.1 ASCII and binary, MSH 2.2 ASCII;
/// docs/formulation.md §7). libgmsh is not linked: it is GPL.
///
/// This is file data only (io/ knows no FE types): Gmsh element type codes, Gmsh's own
/// local node order, physical groups by tag and name. fe/gmsh_mesh.hpp turns it into a
/// Mesh (node orderings mapped, groups turned into regions and boundary node sets).
///
/// Errors throw FileError with one line naming the file, and the line (ASCII) or section
/// and byte offset (binary), and what is wrong.

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

namespace softhd::io {

/// Gmsh element type codes the reader keeps (others are refused when they are of the
/// mesh's top dimension, and skipped with a note when lower-dimensional, e.g. points).
enum GmshElementType : int {
  kGmshLine2 = 1,
  kGmshTri3 = 2,
  kGmshQuad4 = 3,
  kGmshTet4 = 4,
  kGmshHex8 = 5,
  kGmshLine3 = 8,
  kGmshTri6 = 9,
  kGmshQuad9 = 10,
  kGmshTet10 = 11,
  kGmshHex27 = 12,
  kGmshPoint = 15,
};

/// Number of nodes of a kept Gmsh element type, 0 for any other code.
int gmsh_nodes_per_element(int gmsh_type);
/// Dimension of a kept Gmsh element type (0 point, 1 line, 2 surface, 3 volume), -1 else.
int gmsh_element_dim(int gmsh_type);

/// A physical group: its dimension, tag and name ("" if the file gives none).
struct MshPhysicalGroup {
  int dim = 0;       ///< 0 point, 1 curve, 2 surface, 3 volume
  int tag = 0;       ///< the group's tag
  std::string name;  ///< its name ("" if none)
};

/// The elements of one Gmsh type on one geometric entity (MSH 4.1 block; in MSH 2.2 the
/// reader groups consecutive elements of the same type, entity and physical tag).
struct MshElementBlock {
  int gmsh_type = 0;  ///< a GmshElementType
  int dim = 0;        ///< gmsh_element_dim(gmsh_type)
  int entity = 0;     ///< geometric entity tag
  /// Physical group tags of the entity (MSH 4.1 $Entities; MSH 2.2 the element's first
  /// tag). Empty if the entity belongs to no physical group.
  std::vector<int> physical_tags;
  /// Element rows of node indices, compacted to 0..num_nodes-1, in Gmsh's local order.
  Eigen::Matrix<int, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> nodes;
  /// Gmsh element tags, one per row (for messages and $ElementData).
  std::vector<std::int64_t> element_tags;
};

/// A $NodeData or $ElementData block (e.g. a fibre field): its name, components and
/// values per node or element, in file tag order (tags mapped to indices).
struct MshDataBlock {
  std::string name;          ///< the block's string tag
  bool per_element = false;  ///< $ElementData (true) or $NodeData (false)
  int components = 1;        ///< values per node or element
  /// Node indices (compacted) or element tags, one per row of `values`.
  std::vector<std::int64_t> tags;
  Eigen::MatrixXd values;  ///< tags.size() by components
};

/// A whole mesh file.
struct MshFile {
  std::string source;   ///< the file name (for messages)
  double version = 0;   ///< 2.2 or 4.1
  bool binary = false;  ///< MSH 4.1 binary
  /// N by 3 node coordinates (z = 0 for planar meshes), compacted in increasing tag order.
  Eigen::MatrixXd nodes;
  /// Gmsh node tag of each compacted node.
  std::vector<std::int64_t> node_tags;
  std::vector<MshPhysicalGroup> physical_groups;  ///< $PhysicalNames (and tags in use)
  std::vector<MshElementBlock> blocks;            ///< the kept elements, by type and entity
  std::vector<MshDataBlock> data;                 ///< $NodeData and $ElementData blocks
  /// Lines the reader noted and skipped (e.g. point elements, unknown sections).
  std::vector<std::string> notes;

  /// The highest dimension of any element block (0 if none).
  int max_element_dim() const;
  /// The physical group of dimension `dim` called `name`, or null.
  const MshPhysicalGroup* group(int dim, const std::string& name) const;
};

/// What a file's section headers tell before its nodes and elements are read: the node
/// count of $Nodes and the element count per Gmsh type (MSH 4.1: each block's header, its
/// rows skipped; MSH 2.2: each element's type field). Nothing is stored per node or element.
struct MshCounts {
  std::size_t nodes = 0;                ///< nodes the file defines
  std::map<int, std::size_t> elements;  ///< Gmsh type code -> elements of that type
};

/// The counts of a mesh file's bytes (a scan of a fraction of the parse's cost), or false
/// if the scan stops on something malformed (parse_msh then names it).
bool scan_msh_counts(const std::string& bytes, MshCounts* counts);

/// Parses the bytes of a mesh file; `source` names it in messages (a UTF-8 byte order mark
/// before $MeshFormat is skipped). Throws FileError.
MshFile parse_msh(const std::string& bytes, const std::string& source);

/// Called by read_msh with the file's counts before its nodes and elements are parsed; it
/// may throw to refuse the file (e.g. a memory estimate).
using MshCountsCheck = std::function<void(const MshCounts&)>;

/// Reads and parses a mesh file. Throws FileError (also when it cannot be opened, is not a
/// regular file, or does not start with $MeshFormat: checked on its first bytes, so a
/// device or a large file of another kind is not read). `check`, if set, gets the counts
/// of the whole file before the parse.
MshFile read_msh(const std::string& path, const MshCountsCheck& check = nullptr);

}  // namespace softhd::io

// MSH 4.1 (ASCII and binary): $Entities, $Nodes and $Elements. The same code reads both
// encodings: Input reads a token or a binary value as the file is.
#include <climits>
#include <string>
#include <vector>

#include "msh_internal.hpp"

namespace softhd::io::msh_detail {
namespace {

// One entity of $Entities: its tag, bounding box (points: their 3 coordinates), physical
// tags and, but for points, its bounding entities.
void read_entity(Parse& p, int dim) {
  Input& in = p.in;
  const bool bin = in.binary();
  const int tag = in.int_value("an entity tag", INT_MIN, INT_MAX);
  const int coordinates = dim == 0 ? 3 : 6;
  for (int c = 0; c < coordinates; ++c) in.real("a bounding box coordinate");
  const std::size_t n = in.count("the number of physical tags", bin ? 4 : 2);
  std::vector<int> physical;
  physical.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    physical.push_back(in.int_value("a physical tag", INT_MIN, INT_MAX));
  }
  if (dim > 0) {
    const std::size_t m = in.count("the number of bounding entities", bin ? 4 : 2);
    for (std::size_t i = 0; i < m; ++i) in.int_value("a bounding entity tag", INT_MIN, INT_MAX);
  }
  if (!p.entities.emplace(std::make_pair(dim, tag), std::move(physical)).second) {
    in.fail("entity " + std::to_string(tag) + " of dimension " + std::to_string(dim) +
            " is defined twice");
  }
}

// One block of $Nodes, appended to tags and xyz; `left` is how many nodes the section
// header still allows.
void read_node_block(Parse& p, std::size_t left, std::vector<std::int64_t>& tags,
                     std::vector<double>& xyz) {
  Input& in = p.in;
  const bool bin = in.binary();
  const int dim = in.int_value("an entity dimension", 0, 3);
  in.int_value("an entity tag", INT_MIN, INT_MAX);
  const int parametric = in.int_value("the parametric flag", 0, 1);
  const std::size_t n = in.count("the number of nodes in the block", bin ? 32 : 8);
  if (n > left) {
    in.fail("the node blocks hold more nodes than the " + std::to_string(tags.size() + left) +
            " the section declares");
  }
  for (std::size_t i = 0; i < n; ++i) tags.push_back(in.size_tag("a node tag"));
  const int extra = parametric != 0 ? dim : 0;
  for (std::size_t i = 0; i < n; ++i) {
    for (int c = 0; c < 3; ++c) xyz.push_back(in.real("coordinate"));
    for (int c = 0; c < extra; ++c) in.real("parametric coordinate");
  }
}

// A block of a type the reader does not keep: skipped (binary: if its node count is
// known), and remembered for the top-dimension check. Returns its element count.
std::size_t skip_element_block(Parse& p, int dim, int type, const Mark& at) {
  Input& in = p.in;
  if (in.binary()) {
    const int nodes = other_element_type(type).first;
    if (nodes == 0) in.fail_at(at, "unknown element type " + std::to_string(type));
    const std::size_t row = 8 * (1 + static_cast<std::size_t>(nodes));
    const std::size_t n = in.count("the number of elements in the block", row);
    in.skip_bytes(n * row, "the block's elements");
    p.skipped.push_back({type, dim, n, at});
    return n;
  }
  const std::size_t n = in.count("the number of elements in the block", 4);
  in.end_line(true);
  for (std::size_t i = 0; i < n; ++i) in.end_line(false);  // one element a line
  p.skipped.push_back({type, dim, n, at});
  return n;
}

// One block of $Elements; returns its element count (at most `left`).
std::size_t read_element_block(Parse& p, std::size_t left) {
  Input& in = p.in;
  const int dim = in.int_value("an entity dimension", 0, 3);
  const int entity = in.int_value("an entity tag", INT_MIN, INT_MAX);
  const int type = in.int_value("an element type", INT_MIN, INT_MAX);
  const Mark at = in.mark();
  const int nodes = gmsh_nodes_per_element(type);
  if (nodes == 0) {
    const std::size_t n = skip_element_block(p, dim, type, at);
    if (n > left) in.fail_at(at, "the element blocks hold more elements than declared");
    return n;
  }
  if (gmsh_element_dim(type) != dim) {
    in.fail("element type " + std::to_string(type) + " is of dimension " +
            std::to_string(gmsh_element_dim(type)) + ", in a block of entity dimension " +
            std::to_string(dim));
  }
  const std::size_t per = 1 + static_cast<std::size_t>(nodes);
  const std::size_t n =
      in.count("the number of elements in the block", per * (in.binary() ? 8 : 2));
  if (n > left) in.fail("the element blocks hold more elements than declared");
  MshElementBlock b;
  b.gmsh_type = type;
  b.dim = dim;
  b.entity = entity;
  const auto e = p.entities.find({dim, entity});
  if (e != p.entities.end()) {
    b.physical_tags = e->second;
  } else if (p.have_entities) {
    p.out.notes.push_back("entity " + std::to_string(entity) + " of dimension " +
                          std::to_string(dim) + " is not in $Entities: no physical groups");
  }
  b.nodes.resize(static_cast<Eigen::Index>(n), nodes);
  b.element_tags.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    b.element_tags[i] = in.size_tag("an element tag");
    for (int j = 0; j < nodes; ++j) {
      b.nodes(static_cast<Eigen::Index>(i), j) = node_index(p, in.size_tag("a node tag"));
    }
  }
  p.out.blocks.push_back(std::move(b));
  return n;
}

}  // namespace

void read_entities_v4(Parse& p) {
  Input& in = p.in;
  const bool bin = in.binary();
  // smallest entity of each dimension: ASCII 2 bytes a number; binary its fixed fields
  const std::size_t ascii_min[4] = {10, 18, 18, 18};
  const std::size_t binary_min[4] = {36, 68, 68, 68};
  const char* what[4] = {"the number of point entities", "the number of curve entities",
                         "the number of surface entities", "the number of volume entities"};
  std::size_t n[4];
  for (int d = 0; d < 4; ++d) n[d] = in.count(what[d], bin ? binary_min[d] : ascii_min[d]);
  for (int d = 0; d < 4; ++d) {
    for (std::size_t i = 0; i < n[d]; ++i) read_entity(p, d);
  }
  in.expect("$EndEntities");
  p.have_entities = true;
}

void read_nodes_v4(Parse& p) {
  Input& in = p.in;
  const bool bin = in.binary();
  const Mark at = in.mark();
  const std::size_t blocks = in.count("the number of node blocks", bin ? 20 : 8);
  const std::size_t total = in.count("the number of nodes", bin ? 32 : 8);
  if (total > static_cast<std::size_t>(INT_MAX)) in.fail("more nodes than an int index holds");
  in.size_value("the smallest node tag");
  in.size_value("the largest node tag");
  std::vector<std::int64_t> tags;
  std::vector<double> xyz;
  tags.reserve(total);
  xyz.reserve(3 * total);
  for (std::size_t b = 0; b < blocks; ++b) read_node_block(p, total - tags.size(), tags, xyz);
  if (tags.size() != total) {
    in.fail("the node blocks hold " + std::to_string(tags.size()) +
            " nodes, the section declares " + std::to_string(total));
  }
  in.expect("$EndNodes");
  set_nodes(p, tags, xyz, at);
}

void read_elements_v4(Parse& p) {
  Input& in = p.in;
  const bool bin = in.binary();
  const std::size_t blocks = in.count("the number of element blocks", bin ? 20 : 8);
  const std::size_t total = in.count("the number of elements", bin ? 16 : 4);
  in.size_value("the smallest element tag");
  in.size_value("the largest element tag");
  std::size_t seen = 0;
  for (std::size_t b = 0; b < blocks; ++b) seen += read_element_block(p, total - seen);
  if (seen != total) {
    in.fail("the element blocks hold " + std::to_string(seen) + " elements, the section declares " +
            std::to_string(total));
  }
  in.expect("$EndElements");
}

}  // namespace softhd::io::msh_detail

// The counts of a mesh file before its parse (msh.hpp: scan_msh_counts): the $Nodes header,
// and the type and size of every element block (MSH 4.1) or element (MSH 2.2), their node
// tags skipped unread. The other sections are skipped to their end marker.
#include <climits>
#include <string>

#include "msh_internal.hpp"
#include "softhd/error.hpp"

namespace softhd::io {
namespace {

using msh_detail::Input;
using msh_detail::Parse;

// The nodes per element of a Gmsh type, kept or not (fails on an unknown type).
std::size_t nodes_of(Input& in, int type) {
  const int kept = gmsh_nodes_per_element(type);
  const int nodes = kept > 0 ? kept : msh_detail::other_element_type(type).first;
  if (nodes == 0) in.fail("unknown element type " + std::to_string(type));
  return static_cast<std::size_t>(nodes);
}

// `n` rows of `per` values (8-byte binary or ASCII tokens) skipped.
void skip_rows(Input& in, std::size_t n, std::size_t per) {
  if (in.binary()) {
    in.skip_bytes(n * per * 8, "the block's elements");
    return;
  }
  for (std::size_t k = 0; k < n * per; ++k) in.token("a node tag");
}

void scan_elements_v4(Input& in, MshCounts* c) {
  const bool bin = in.binary();
  const std::size_t blocks = in.count("the number of element blocks", bin ? 20 : 8);
  in.count("the number of elements", bin ? 16 : 4);
  in.size_value("the smallest element tag");
  in.size_value("the largest element tag");
  for (std::size_t b = 0; b < blocks; ++b) {
    in.int_value("an entity dimension", 0, 3);
    in.int_value("an entity tag", INT_MIN, INT_MAX);
    const int type = in.int_value("an element type", INT_MIN, INT_MAX);
    const std::size_t per = 1 + nodes_of(in, type);  // the tag and the nodes
    const std::size_t n = in.count("the number of elements in the block", per * (bin ? 8 : 2));
    skip_rows(in, n, per);
    c->elements[type] += n;
  }
}

void scan_elements_v2(Input& in, MshCounts* c) {
  const std::size_t n = in.count("the number of elements", 8);
  for (std::size_t i = 0; i < n; ++i) {
    in.size_tag("an element tag");
    const int type = in.int_value("an element type", INT_MIN, INT_MAX);
    const std::size_t tags = in.count("the number of tags", 2);
    skip_rows(in, 1, tags + nodes_of(in, type));
    ++c->elements[type];
  }
}

// The $Nodes header (4.1: blocks, then the node count), the section skipped.
void scan_nodes(Input& in, bool v4, MshCounts* c) {
  const bool bin = in.binary();
  if (v4) in.count("the number of node blocks", bin ? 20 : 8);
  c->nodes = in.count("the number of nodes", bin ? 32 : 8);
  in.skip_section("$Nodes");
}

}  // namespace

bool scan_msh_counts(const std::string& bytes, MshCounts* counts) {
  MshFile file;
  Input in(bytes, "");
  Parse p(in, file);
  MshCounts c;
  try {
    msh_detail::read_format(p);
    const bool v4 = file.version > 3;
    bool nodes = false, elements = false;
    while (!(nodes && elements) && !in.at_end()) {
      const std::string name(in.token("a section"));
      if (name.size() < 2 || name[0] != '$') return false;
      if (in.binary() && (name == "$Nodes" || name == "$Elements")) in.end_line(true);
      if (name == "$Nodes" && !nodes) {
        scan_nodes(in, v4, &c);
        nodes = true;
      } else if (name == "$Elements" && !elements) {
        v4 ? scan_elements_v4(in, &c) : scan_elements_v2(in, &c);
        elements = true;
      } else {
        in.skip_section(name);
      }
    }
    if (!(nodes && elements)) return false;
  } catch (const FileError&) {
    return false;
  }
  *counts = std::move(c);
  return true;
}

}  // namespace softhd::io

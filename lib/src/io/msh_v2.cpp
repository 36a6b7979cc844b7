// MSH 2.2 (ASCII): $Nodes and $Elements. Elements come one a line with their tags (the
// first is the physical group, the second the geometric entity); consecutive elements of
// one type, entity and physical group make a block.
#include <climits>
#include <string>
#include <vector>

#include "msh_internal.hpp"

namespace softhd::io::msh_detail {
namespace {

// The block being collected.
struct Run {
  int type = 0;
  int entity = 0;
  int physical = 0;
  std::vector<int> nodes;
  std::vector<std::int64_t> tags;
};

void flush(Parse& p, Run& run) {
  if (run.tags.empty()) return;
  MshElementBlock b;
  b.gmsh_type = run.type;
  b.dim = gmsh_element_dim(run.type);
  b.entity = run.entity;
  if (run.physical != 0) b.physical_tags.push_back(run.physical);
  const int per = gmsh_nodes_per_element(run.type);
  const auto n = static_cast<Eigen::Index>(run.tags.size());
  b.nodes = Eigen::Map<const Eigen::Matrix<int, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
      run.nodes.data(), n, per);
  b.element_tags = std::move(run.tags);
  p.out.blocks.push_back(std::move(b));
  run.tags.clear();
  run.nodes.clear();
}

// An element of a type the reader does not keep: the rest of its line skipped, counted
// with the run of skipped elements of its type.
void skip_element(Parse& p, int type, const Mark& at) {
  Input& in = p.in;
  const int dim = other_element_type(type).second;
  if (dim < 0) in.fail_at(at, "unknown element type " + std::to_string(type));
  in.end_line(false);
  if (!p.skipped.empty() && p.skipped.back().gmsh_type == type) {
    ++p.skipped.back().count;
  } else {
    p.skipped.push_back({type, dim, 1, at});
  }
}

}  // namespace

void read_nodes_v2(Parse& p) {
  Input& in = p.in;
  const Mark at = in.mark();
  const std::size_t n = in.count("the number of nodes", 8);
  if (n > static_cast<std::size_t>(INT_MAX)) in.fail("more nodes than an int index holds");
  std::vector<std::int64_t> tags;
  std::vector<double> xyz;
  tags.reserve(n);
  xyz.reserve(3 * n);
  for (std::size_t i = 0; i < n; ++i) {
    tags.push_back(in.size_tag("a node tag"));
    for (int c = 0; c < 3; ++c) xyz.push_back(in.real("coordinate"));
  }
  in.expect("$EndNodes");
  set_nodes(p, tags, xyz, at);
}

void read_elements_v2(Parse& p) {
  Input& in = p.in;
  const std::size_t n = in.count("the number of elements", 8);
  Run run;
  for (std::size_t i = 0; i < n; ++i) {
    const std::int64_t tag = in.size_tag("an element tag");
    const int type = in.int_value("an element type", INT_MIN, INT_MAX);
    const Mark at = in.mark();
    const std::size_t ntags = in.count("the number of tags", 2);
    int physical = 0;
    int entity = 0;
    for (std::size_t k = 0; k < ntags; ++k) {
      const int v = in.int_value("a tag", INT_MIN, INT_MAX);
      if (k == 0) physical = v;
      if (k == 1) entity = v;
    }
    const int per = gmsh_nodes_per_element(type);
    if (per == 0) {
      skip_element(p, type, at);
      continue;
    }
    if (type != run.type || entity != run.entity || physical != run.physical) {
      flush(p, run);
      run.type = type;
      run.entity = entity;
      run.physical = physical;
    }
    run.tags.push_back(tag);
    for (int j = 0; j < per; ++j) run.nodes.push_back(node_index(p, in.size_tag("a node tag")));
  }
  flush(p, run);
  in.expect("$EndElements");
}

}  // namespace softhd::io::msh_detail

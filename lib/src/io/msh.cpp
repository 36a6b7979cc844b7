// Gmsh MSH files (msh.hpp): the element type tables, the sections common to MSH 2.2 and
// 4.1 ($MeshFormat, $PhysicalNames, $NodeData, $ElementData), the section loop and the
// checks at the end. The versions' $Nodes, $Elements and $Entities are in msh_v2.cpp and
// msh_v4.cpp, the input cursor in msh_input.cpp.
#include "softhd/io/msh.hpp"

#include <algorithm>
#include <cerrno>
#include <climits>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>
#include <numeric>
#include <set>

#include "msh_internal.hpp"
#include "softhd/error.hpp"

namespace softhd::io {

int gmsh_nodes_per_element(int gmsh_type) {
  switch (gmsh_type) {
    case kGmshPoint:
      return 1;
    case kGmshLine2:
      return 2;
    case kGmshLine3:
      return 3;
    case kGmshTri3:
      return 3;
    case kGmshTri6:
      return 6;
    case kGmshQuad4:
      return 4;
    case kGmshQuad9:
      return 9;
    case kGmshTet4:
      return 4;
    case kGmshTet10:
      return 10;
    case kGmshHex8:
      return 8;
    case kGmshHex27:
      return 27;
    default:
      return 0;
  }
}

int gmsh_element_dim(int gmsh_type) {
  switch (gmsh_type) {
    case kGmshPoint:
      return 0;
    case kGmshLine2:
    case kGmshLine3:
      return 1;
    case kGmshTri3:
    case kGmshTri6:
    case kGmshQuad4:
    case kGmshQuad9:
      return 2;
    case kGmshTet4:
    case kGmshTet10:
    case kGmshHex8:
    case kGmshHex27:
      return 3;
    default:
      return -1;
  }
}

int MshFile::max_element_dim() const {
  int dim = 0;
  for (const MshElementBlock& b : blocks) dim = std::max(dim, b.dim);
  return dim;
}

const MshPhysicalGroup* MshFile::group(int dim, const std::string& name) const {
  for (const MshPhysicalGroup& g : physical_groups) {
    if (g.dim == dim && g.name == name) return &g;
  }
  return nullptr;
}

namespace msh_detail {

std::pair<int, int> other_element_type(int gmsh_type) {
  // Gmsh's codes of the types the reader does not keep: {nodes, dim}.
  struct Other {
    int type, nodes, dim;
  };
  static constexpr Other kOthers[] = {
      {6, 6, 3},   {7, 5, 3},   {13, 18, 3}, {14, 14, 3}, {16, 8, 2},  {17, 20, 3},
      {18, 15, 3}, {19, 13, 3}, {20, 9, 2},  {21, 10, 2}, {22, 12, 2}, {23, 15, 2},
      {24, 15, 2}, {25, 21, 2}, {26, 4, 1},  {27, 5, 1},  {28, 6, 1},  {29, 20, 3},
      {30, 35, 3}, {31, 56, 3}, {92, 64, 3}, {93, 125, 3}};
  for (const Other& o : kOthers) {
    if (o.type == gmsh_type) return {o.nodes, o.dim};
  }
  return {0, -1};
}

void set_nodes(Parse& p, std::vector<std::int64_t>& tags, std::vector<double>& xyz,
               const Mark& at) {
  const std::size_t n = tags.size();
  std::vector<std::size_t> order(n);
  std::iota(order.begin(), order.end(), std::size_t{0});
  if (!std::is_sorted(tags.begin(), tags.end())) {
    std::sort(order.begin(), order.end(),
              [&](std::size_t a, std::size_t b) { return tags[a] < tags[b]; });
  }
  MshFile& out = p.out;
  out.nodes.resize(static_cast<Eigen::Index>(n), 3);
  out.node_tags.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t k = order[i];
    if (i > 0 && tags[k] == out.node_tags[i - 1]) {
      p.in.fail_at(at, "node tag " + std::to_string(tags[k]) + " is defined twice");
    }
    out.node_tags[i] = tags[k];
    for (int c = 0; c < 3; ++c) out.nodes(static_cast<Eigen::Index>(i), c) = xyz[3 * k + c];
  }
  p.have_nodes = true;
}

int node_index(const Parse& p, std::int64_t tag) {
  const std::vector<std::int64_t>& tags = p.out.node_tags;
  const auto it = std::lower_bound(tags.begin(), tags.end(), tag);
  if (it == tags.end() || *it != tag) {
    p.in.fail("node tag " + std::to_string(tag) + " is not defined in $Nodes");
  }
  return static_cast<int>(it - tags.begin());
}

void read_format(Parse& p) {
  Input& in = p.in;
  in.skip_prefix("\xEF\xBB\xBF");  // a UTF-8 byte order mark, as some editors write
  if (in.at_end() || in.token("$MeshFormat") != "$MeshFormat") {
    in.fail("not a Gmsh mesh file (it does not start with $MeshFormat)");
  }
  const std::string_view version = in.token("the MSH version");
  if (version == "4.1") {
    p.out.version = 4.1;
  } else if (version == "2.2" || version == "2.1" || version == "2.0" || version == "2") {
    p.out.version = 2.2;
  } else {
    in.fail("MSH version '" + std::string(version.substr(0, 20)) +
            "' is not read (MSH 4.1 and 2.2 are; re-save the mesh from Gmsh in one of them)");
  }
  const bool binary = in.ascii_integer("the file type", 0, 1) == 1;
  const long long data_size = in.ascii_integer("the data size", LLONG_MIN, LLONG_MAX);
  if (data_size != 8) in.fail("data size " + std::to_string(data_size) + " is not 8");
  if (binary && p.out.version < 4) in.fail("binary MSH 2.2 is not read (save as ASCII or 4.1)");
  p.out.binary = binary;
  if (binary) {
    in.set_binary(true);
    in.set_section("$MeshFormat");
    in.end_line(true);
    if (in.int_value("the endianness check", INT_MIN, INT_MAX) != 1) {
      in.fail("the endianness check is not 1 (a big-endian or damaged file)");
    }
  }
  in.expect("$EndMeshFormat");
}

}  // namespace msh_detail

namespace {

using msh_detail::Input;
using msh_detail::Mark;
using msh_detail::Parse;

void read_physical_names(Parse& p) {
  Input& in = p.in;
  const std::size_t n = in.ascii_count("the number of physical names", 8);
  std::set<std::pair<int, int>> seen;
  for (std::size_t i = 0; i < n; ++i) {
    MshPhysicalGroup g;
    g.dim = static_cast<int>(in.ascii_integer("a physical group's dimension", 0, 3));
    g.tag = static_cast<int>(in.ascii_integer("a physical tag", INT_MIN, INT_MAX));
    g.name = in.quoted("a physical group's name");
    if (!seen.insert({g.dim, g.tag}).second) {
      in.fail("physical group " + std::to_string(g.tag) + " of dimension " + std::to_string(g.dim) +
              " is named twice");
    }
    p.out.physical_groups.push_back(std::move(g));
  }
  in.expect("$EndPhysicalNames");
}

// The string, real and integer tags of a data block; returns the number of rows.
std::size_t read_data_header(Parse& p, MshDataBlock& d) {
  Input& in = p.in;
  const std::size_t strings = in.ascii_count("the number of string tags", 3);
  for (std::size_t i = 0; i < strings; ++i) {
    std::string s = in.quoted("a string tag");
    if (i == 0) d.name = std::move(s);
  }
  const std::size_t reals = in.ascii_count("the number of real tags", 2);
  for (std::size_t i = 0; i < reals; ++i) in.ascii_real("a real tag");
  const std::size_t ints = in.ascii_count("the number of integer tags", 2);
  if (ints < 3) {
    in.fail("a data block needs 3 integer tags (time step, components, count), got " +
            std::to_string(ints));
  }
  in.ascii_integer("the time step", LLONG_MIN, LLONG_MAX);
  d.components = static_cast<int>(in.ascii_integer("the number of components", 1, 1024));
  const std::size_t row = in.binary() ? 4 + 8 * static_cast<std::size_t>(d.components)
                                      : 2 * (1 + static_cast<std::size_t>(d.components));
  const std::size_t rows = in.ascii_count("the number of values", row);
  for (std::size_t i = 3; i < ints; ++i) in.ascii_integer("an integer tag", LLONG_MIN, LLONG_MAX);
  if (in.binary()) in.end_line(true);
  return rows;
}

// $NodeData (node tags mapped to indices) or $ElementData (element tags kept, checked).
void read_data(Parse& p, bool per_element) {
  Input& in = p.in;
  if (!(per_element ? p.have_elements : p.have_nodes)) {
    in.fail(per_element ? "$ElementData before $Elements" : "$NodeData before $Nodes");
  }
  MshDataBlock d;
  d.per_element = per_element;
  const Mark at = in.mark();
  const std::size_t rows = read_data_header(p, d);
  for (const MshDataBlock& other : p.out.data)  // a field is looked up by its name
    if (other.name == d.name)
      in.fail_at(at, "a second data block named '" + d.name.substr(0, 60) +
                         "' (softhd reads one block, one time step, per name: rename or "
                         "remove one)");
  d.tags.reserve(rows);
  d.values.resize(static_cast<Eigen::Index>(rows), d.components);
  for (std::size_t r = 0; r < rows; ++r) {
    const std::int64_t tag = in.binary()
                                 ? in.int_value("a tag", 1, INT_MAX)
                                 : in.size_tag(per_element ? "an element tag" : "a node tag");
    if (!per_element) {
      d.tags.push_back(msh_detail::node_index(p, tag));
    } else if (std::binary_search(p.element_tags.begin(), p.element_tags.end(), tag)) {
      d.tags.push_back(tag);
    } else {
      in.fail("element tag " + std::to_string(tag) + " is not defined in $Elements");
    }
    for (int c = 0; c < d.components; ++c) {
      d.values(static_cast<Eigen::Index>(r), c) = in.real("a data value");
    }
  }
  in.expect(per_element ? "$EndElementData" : "$EndNodeData");
  p.out.data.push_back(std::move(d));
}

// Sorted element tags (for $ElementData), refusing duplicates.
void index_elements(Parse& p, const Mark& at) {
  std::vector<std::int64_t>& tags = p.element_tags;
  for (const MshElementBlock& b : p.out.blocks) {
    tags.insert(tags.end(), b.element_tags.begin(), b.element_tags.end());
  }
  std::sort(tags.begin(), tags.end());
  const auto dup = std::adjacent_find(tags.begin(), tags.end());
  if (dup != tags.end())
    p.in.fail_at(at, "element tag " + std::to_string(*dup) + " is defined twice");
  p.have_elements = true;
}

void read_section(Parse& p, const std::string& name) {
  Input& in = p.in;
  const Mark at = in.mark();
  const bool v4 = p.out.version > 3;
  const auto once = [&](bool& seen) {
    if (seen) in.fail("a second " + name + " section");
  };
  if (in.binary() && (name == "$Entities" || name == "$Nodes" || name == "$Elements")) {
    in.end_line(true);
  }
  if (name == "$PhysicalNames") {
    read_physical_names(p);
  } else if (name == "$Entities" && v4) {
    once(p.have_entities);
    msh_detail::read_entities_v4(p);
  } else if (name == "$Nodes") {
    once(p.have_nodes);
    v4 ? msh_detail::read_nodes_v4(p) : msh_detail::read_nodes_v2(p);
  } else if (name == "$Elements") {
    once(p.have_elements);
    if (!p.have_nodes) in.fail("$Elements before $Nodes");
    v4 ? msh_detail::read_elements_v4(p) : msh_detail::read_elements_v2(p);
    index_elements(p, at);
  } else if (name == "$NodeData" || name == "$ElementData") {
    read_data(p, name == "$ElementData");
  } else {
    in.skip_section(name);
    p.out.notes.push_back("skipped section " + name.substr(0, 60));
  }
}

// Physical groups that have elements but no name; the top-dimension check on the element
// types the reader skipped.
void finish(Parse& p) {
  Input& in = p.in;
  if (!p.have_nodes) in.fail("no $Nodes section");
  if (!p.have_elements) in.fail("no $Elements section");
  MshFile& out = p.out;
  const int top = out.max_element_dim();
  in.set_section("$Elements");
  for (const msh_detail::SkippedBlock& s : p.skipped) {
    const std::string what = std::to_string(s.count) + " elements of Gmsh type " +
                             std::to_string(s.gmsh_type) + " (dimension " + std::to_string(s.dim) +
                             ")";
    if (s.dim >= top) {
      in.fail_at(s.at,
                 "element type " + std::to_string(s.gmsh_type) + " of the mesh's top dimension " +
                     std::to_string(s.dim) +
                     " is not read (kept: tet4, tet10, hex8, hex27, tri3, tri6, quad4, quad9)");
    }
    out.notes.push_back("skipped " + what);
  }
  std::set<std::pair<int, int>> named;
  for (const MshPhysicalGroup& g : out.physical_groups) named.insert({g.dim, g.tag});
  for (const MshElementBlock& b : out.blocks) {
    for (int tag : b.physical_tags) {
      if (named.insert({b.dim, tag}).second) out.physical_groups.push_back({b.dim, tag, ""});
    }
  }
}

}  // namespace

MshFile parse_msh(const std::string& bytes, const std::string& source) {
  MshFile out;
  out.source = source;
  Input in(bytes, source);
  Parse p(in, out);
  msh_detail::read_format(p);
  while (!in.at_end()) {
    in.set_section("");
    const std::string_view t = in.token("a section");
    if (t.size() < 2 || t[0] != '$') {
      in.fail("expected a section ($Name), got '" + std::string(t.substr(0, 40)) + "'");
    }
    const std::string name(t);
    in.set_section(name.substr(0, 60));
    read_section(p, name);
  }
  in.set_section("");
  finish(p);
  return out;
}

namespace {

// Refuses `head` (the first 64 KiB of `path`, or all of it) unless, after a UTF-8 byte
// order mark and blanks, it starts with $MeshFormat, with parse_msh's message: a point
// cloud or any other large file is refused before it is read whole.
void check_head(const std::string& head, const std::string& path) {
  const std::size_t start = head.rfind("\xEF\xBB\xBF", 0) == 0 ? 3 : 0;
  const std::size_t text = head.find_first_not_of(" \t\r\n\v\f", start);
  if (text != std::string::npos && head.compare(text, 11, "$MeshFormat") == 0) return;
  const auto line = std::count(
      head.begin(), head.begin() + static_cast<std::ptrdiff_t>(std::min(text, head.size())), '\n');
  throw FileError(path + ":" + std::to_string(line + 1) +
                  ": not a Gmsh mesh file (it does not start with $MeshFormat)");
}

}  // namespace

MshFile read_msh(const std::string& path, const MshCountsCheck& check) {
  std::error_code ec;
  const std::filesystem::file_status status = std::filesystem::status(path, ec);
  if (!ec && std::filesystem::exists(status) && !std::filesystem::is_regular_file(status))
    throw FileError("'" + path + "' is not a regular file (a mesh is read from a file)");
  const std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(std::fopen(path.c_str(), "rb"),
                                                          &std::fclose);
  if (!f) throw FileError("cannot open '" + path + "': " + std::strerror(errno));
  const std::uintmax_t size = std::filesystem::file_size(path, ec);
  const bool sized = !ec;
  std::string data;
  char buffer[1 << 16];
  std::size_t got = 0;
  while ((got = std::fread(buffer, 1, sizeof buffer, f.get())) > 0) {
    if (data.empty()) {
      check_head(std::string(buffer, got), path);
      if (sized) data.reserve(static_cast<std::size_t>(size));  // no copies as it grows
    }
    data.append(buffer, got);
  }
  if (std::ferror(f.get()) != 0) throw FileError("cannot read '" + path + "'");
  MshCounts counts;
  if (check && scan_msh_counts(data, &counts)) check(counts);
  return parse_msh(data, path);
}

}  // namespace softhd::io

#include "softhd/control/scene.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "../common/keys.hpp"
#include "softhd/error.hpp"
#include "softhd/fe/dofs.hpp"
#include "softhd/fe/gmsh_mesh.hpp"
#include "softhd/fe/newton.hpp"
#include "softhd/io/cloud_io.hpp"
#include "softhd/io/msh.hpp"

namespace softhd {

namespace {

// The body's types and checks (fe::Body, fe::Mesh, fe::make_dof_map, ...).
using namespace fe;
using nlohmann::json;

// Reads typed values out of a JSON object, naming the full key in every error.
class Reader {
 public:
  explicit Reader(std::string source) : source_(std::move(source)) {}

  // Refuses keys of `object` (at `path`, "" for the top level) outside `allowed`.
  void keys(const json& object, const std::string& path,
            std::initializer_list<const char*> allowed) const {
    io::check_keys(object, "scene " + source_, path, allowed);
  }
  [[noreturn]] void fail(const std::string& key, const std::string& expected) const {
    throw FileError("scene " + source_ + ": key '" + key + "' " + expected);
  }
  const json& object(const json& parent, const std::string& key, const std::string& path) const {
    if (!parent.contains(key)) fail(path, "is missing (expected an object)");
    const json& v = parent.at(key);
    if (!v.is_object()) fail(path, "must be an object");
    return v;
  }
  double number(const json& parent, const std::string& key, const std::string& path) const {
    if (!parent.contains(key)) fail(path, "is missing (expected a number)");
    const json& v = parent.at(key);
    if (!v.is_number()) fail(path, "must be a number, got " + v.dump());
    return v.get<double>();
  }
  std::string string(const json& parent, const std::string& key, const std::string& path) const {
    if (!parent.contains(key)) fail(path, "is missing (expected a string)");
    const json& v = parent.at(key);
    if (!v.is_string()) fail(path, "must be a string, got " + v.dump());
    return v.get<std::string>();
  }
  Eigen::VectorXd numbers(const json& parent, const std::string& key, const std::string& path,
                          int min_size, int max_size) const {
    const std::string expect = "must be an array of " + std::to_string(min_size) +
                               (max_size > min_size ? " or " + std::to_string(max_size) : "") +
                               " numbers";
    if (!parent.contains(key)) fail(path, "is missing (" + expect.substr(5) + ")");
    const json& v = parent.at(key);
    if (!v.is_array() || static_cast<int>(v.size()) < min_size ||
        static_cast<int>(v.size()) > max_size)
      fail(path, expect + ", got " + v.dump());
    Eigen::VectorXd r(v.size());
    for (size_t i = 0; i < v.size(); ++i) {
      if (!v[i].is_number()) fail(path, expect + ", got " + v.dump());
      r[static_cast<Eigen::Index>(i)] = v[i].get<double>();
    }
    return r;
  }

 private:
  std::string source_;
};

std::shared_ptr<const Material> read_material(const Reader& r, const json& m) {
  const std::string model = r.string(m, "model", "material.model");
  if (model == "mooney_rivlin") r.keys(m, "material", {"model", "a", "b", "c"});
  if (model == "transversely_isotropic") r.keys(m, "material", {"model", "a", "b", "c", "d", "f"});
  try {
    if (model == "mooney_rivlin") {
      return std::make_shared<MooneyRivlin>(r.number(m, "a", "material.a"),
                                            r.number(m, "b", "material.b"),
                                            r.number(m, "c", "material.c"));
    }
    if (model == "transversely_isotropic") {
      const Eigen::VectorXd f = r.numbers(m, "f", "material.f", 3, 3);
      return std::make_shared<TransverselyIsotropic>(
          r.number(m, "a", "material.a"), r.number(m, "b", "material.b"),
          r.number(m, "c", "material.c"), r.number(m, "d", "material.d"), Eigen::Vector3d(f));
    }
  } catch (const InvalidArgument& e) {
    r.fail("material", std::string("is invalid: ") + e.what());
  }
  r.fail("material.model",
         "must be \"mooney_rivlin\" or \"transversely_isotropic\", got \"" + model + "\"");
}

// A number for messages: %g (6 significant digits, an exponent when large or small).
std::string shown(double x) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", x);
  return text;
}

// A scene's name names its default output folder (results/<name>): a plain file name of
// letters, digits, '.', '_', '+' and '-', not starting with '.' or '-', at most 100 characters.
bool plain_file_name(const std::string& name) {
  if (name.empty() || name.size() > 100 || name[0] == '.' || name[0] == '-') return false;
  for (char c : name) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                    c == '.' || c == '_' || c == '+' || c == '-';
    if (!ok) return false;
  }
  return true;
}

// The name of a scene without "name": its file name without folder and extension, made plain.
std::string default_name(const std::string& source) {
  std::string stem = source.substr(source.find_last_of('/') + 1);
  stem = stem.substr(0, stem.find_last_of('.'));
  for (char& c : stem)
    if (!plain_file_name(std::string("a") + c)) c = '_';
  while (!stem.empty() && (stem[0] == '.' || stem[0] == '-')) stem.erase(0, 1);
  return plain_file_name(stem) ? stem : "scene";
}

// Lengths and stresses softhd solves in double precision: |Ω₀|, residuals (stress × area)
// and tangents (stress × length) stay far from overflow and underflow, and the state's
// tolerances (relative to stiffness × |Ω₀|^((d-1)/d)) stay meaningful. Tested at both ends
// of both ranges against the unit problem, scaled (tests/fe/test_scene.cpp).
constexpr double kMinLength = 1e-6, kMaxLength = 1e6;
constexpr double kMinStress = 1e-6, kMaxStress = 1e12;

void check_scales(const Reader& r, const Body& s) {
  const double size = (s.upper - s.lower).maxCoeff();
  const char* where = s.is_box() ? "mesh.upper" : "mesh.scale";
  if (!(size >= kMinLength && size <= kMaxLength))
    r.fail(where, "gives a body of size " + shown(size) +
                      ": softhd solves bodies from 1e-6 to 1e6 in size (change units)");
  for (int d = 0; d < s.dim(); ++d)
    if (!(std::abs(s.lower[d]) <= 1e3 * kMaxLength))
      r.fail(s.is_box() ? "mesh.lower" : "mesh.scale",
             "must lie within 1e9 of the origin (change units or origin)");
  for (const auto& m : s.materials) {
    const double stress = m->stiffness_scale();
    if (!(stress >= kMinStress && stress <= kMaxStress))
      r.fail(s.materials.size() > 1 ? "materials" : "material",
             "has a stiffness of " + shown(stress) +
                 ": softhd solves stiffnesses from 1e-6 to 1e12 (change units)");
  }
}

}  // namespace

namespace {

void parse_box_mesh(const Reader& r, const json& mesh, double memory_limit, Body* s) {
  r.keys(mesh, "mesh", {"type", "lower", "upper", "cells", "order", "quadrature_degree"});
  s->lower = r.numbers(mesh, "lower", "mesh.lower", 2, 3);
  s->upper = r.numbers(mesh, "upper", "mesh.upper", 2, 3);
  if (s->upper.size() != s->lower.size()) r.fail("mesh.upper", "must have the size of mesh.lower");
  for (int d = 0; d < s->dim(); ++d)
    if (!(s->upper[d] > s->lower[d])) r.fail("mesh.upper", "must be > mesh.lower on every axis");
  const Eigen::VectorXd cells = r.numbers(mesh, "cells", "mesh.cells", s->dim(), s->dim());
  s->cells.resize(s->dim());
  for (int d = 0; d < s->dim(); ++d) {
    if (!(cells[d] >= 1) || cells[d] != std::floor(cells[d]) || cells[d] > 1e6)
      r.fail("mesh.cells", "must hold positive integers, got " + std::to_string(cells[d]));
    s->cells[d] = static_cast<int>(cells[d]);
  }
  const double order = r.number(mesh, "order", "mesh.order");
  if (order != 1 && order != 2) r.fail("mesh.order", "must be 1 or 2");
  s->order = static_cast<int>(order);
  check_mesh_size(box_mesh_size(cells, s->order), memory_limit,
                  "scene " + s->source + ": the mesh");
  s->volume = (s->upper - s->lower).prod();
}

// mesh.type "gmsh": the file (relative to the scene's folder) read and turned into the mesh.
void parse_gmsh_mesh(const Reader& r, const json& mesh, double memory_limit, Body* s) {
  r.keys(mesh, "mesh", {"type", "file", "order", "scale", "quadrature_degree"});
  GmshMeshOptions o;
  if (mesh.contains("order")) {
    const double order = r.number(mesh, "order", "mesh.order");
    if (order != 1 && order != 2) r.fail("mesh.order", "must be 1 or 2 (or absent: the file's)");
    o.order = static_cast<int>(order);
  }
  if (mesh.contains("scale")) {
    o.scale = r.number(mesh, "scale", "mesh.scale");
    if (!(o.scale >= GmshMeshOptions::kMinScale && o.scale <= GmshMeshOptions::kMaxScale))
      r.fail("mesh.scale", "must be in [1e-12, 1e12], got " + shown(o.scale));
  }
  const std::filesystem::path dir = std::filesystem::path(s->source).parent_path();
  s->mesh_file = (dir / r.string(mesh, "file", "mesh.file")).lexically_normal().string();
  s->gmsh_options = o;
  s->file_mesh = std::make_shared<Mesh>(read_gmsh_mesh(s->mesh_file, o, &s->volume, memory_limit));
  const Mesh& m = *s->file_mesh;
  s->order = m.order;
  s->lower = m.nodes.colwise().minCoeff().transpose();
  s->upper = m.nodes.colwise().maxCoeff().transpose();
}

// "material" (the whole body) or "materials" (one per region of the mesh, by name).
void parse_materials(const Reader& r, const json& doc, const Mesh& mesh, Body* s) {
  if (doc.contains("material") == doc.contains("materials"))
    r.fail("material",
           "give either \"material\" (the whole body) or \"materials\" (one per "
           "region of the mesh), not both or neither");
  if (doc.contains("material")) {
    s->materials.assign(mesh.region_names.size(),
                        read_material(r, r.object(doc, "material", "material")));
    return;
  }
  const json& all = r.object(doc, "materials", "materials");
  s->materials.assign(mesh.region_names.size(), nullptr);
  for (const auto& item : all.items()) {
    int region = -1;
    try {
      region = mesh.region(item.key());
    } catch (const InvalidArgument& e) {
      r.fail("materials", e.what());
    }
    if (!item.value().is_object()) r.fail("materials." + item.key(), "must be an object");
    s->materials[region] = read_material(r, item.value());
  }
  for (std::size_t k = 0; k < s->materials.size(); ++k)
    if (!s->materials[k])
      r.fail("materials", "has no material for region '" + mesh.region_names[k] + "'");
}

// Per-node fibres given at the vertices of an order-2 mesh (one row per node of a first-order
// file that "order": 2 elevated): every other node takes the mean axis of its support's
// vertices (its edge's, face's or cell's), as the elevated nodes of a $NodeData block do.
Eigen::Matrix3Xd fibers_from_vertices(const Eigen::Matrix3Xd& at_vertex, const Mesh& mesh) {
  const ReferenceElement& ref = reference_element(mesh.cell);
  Eigen::Matrix3Xd a = Eigen::Matrix3Xd::Zero(3, mesh.num_nodes());
  std::vector<char> done(static_cast<std::size_t>(mesh.num_nodes()), 0);
  for (Eigen::Index k = 0; k < mesh.num_vertices(); ++k) {
    a.col(mesh.vertex_nodes[k]) = at_vertex.col(k);
    done[static_cast<std::size_t>(mesh.vertex_nodes[k])] = 1;
  }
  for (Eigen::Index e = 0; e < mesh.num_elements(); ++e)
    for (int l = 0; l < ref.nodes; ++l) {
      const int n = mesh.elements(e, l);
      if (done[static_cast<std::size_t>(n)]) continue;
      const std::vector<int>& support = ref.node_support[static_cast<std::size_t>(l)];
      Eigen::Matrix3Xd v(3, static_cast<Eigen::Index>(support.size()));
      for (std::size_t j = 0; j < support.size(); ++j)
        v.col(static_cast<Eigen::Index>(j)) =
            a.col(mesh.elements(e, ref.vertex_nodes[static_cast<std::size_t>(support[j])]));
      a.col(n) = aligned_fibers(v).rowwise().mean();
      done[static_cast<std::size_t>(n)] = 1;
    }
  return a;
}

// A fibre field from a text file: rows of 3 numbers (io's cloud reader), one per element or
// per node of the mesh (or, on an order-2 mesh, per vertex: fibers_from_vertices).
FiberField read_fiber_file(const std::string& path, bool per_element, const Mesh& mesh) {
  FiberField f;
  f.kind = per_element ? FiberField::Kind::kElement : FiberField::Kind::kNode;
  const Eigen::MatrixXd rows = read_cloud(path, 3).points();
  const Eigen::Index expected = per_element ? mesh.num_elements() : mesh.num_nodes();
  const bool vertices = !per_element && mesh.order == 2 && rows.rows() == mesh.num_vertices();
  if (rows.rows() != expected && !vertices)
    throw FileError(path + ": " + std::to_string(rows.rows()) + " fibre rows for the mesh's " +
                    std::to_string(expected) +
                    (per_element ? " elements"
                     : mesh.order == 2
                         ? " nodes (or one per vertex, " + std::to_string(mesh.num_vertices()) +
                               ", in node order: the others take their edge's mean axis)"
                         : " nodes"));
  for (Eigen::Index k = 0; k < rows.rows(); ++k)
    if (!(rows.row(k).norm() > 0.0) || !rows.row(k).allFinite())
      throw FileError(path + ": row " + std::to_string(k + 1) +
                      " is a zero or non-finite fibre vector");
  f.values = rows.transpose();
  if (vertices && rows.rows() != expected) f.values = fibers_from_vertices(f.values, mesh);
  return f;
}

// "fibers": a vector; {"data": NAME} (a $NodeData / $ElementData block of the mesh file);
// {"file": PATH, "per": "element" | "node"} (rows of 3 numbers).
void parse_fibers(const Reader& r, const json& doc, const Mesh& mesh, Body* s) {
  if (!doc.contains("fibers") || !doc["fibers"].is_object()) {
    const Eigen::VectorXd f = r.numbers(doc, "fibers", "fibers", 3, 3);
    if (!(f.norm() > 0.0)) r.fail("fibers", "must be a non-zero vector");
    if (s->dim() == 2 && f[2] != 0.0) r.fail("fibers", "must have a zero third component in 2D");
    s->fiber_field.values = f.normalized();
    return;
  }
  const json& f = doc["fibers"];
  r.keys(f, "fibers", {"data", "file", "per"});
  if (s->is_box()) r.fail("fibers", "a fibre field needs a mesh from a file (mesh.type \"gmsh\")");
  if (f.contains("data")) {
    const std::string name = r.string(f, "data", "fibers.data");
    try {
      s->fiber_field = gmsh_fiber_field(io::read_msh(s->mesh_file), name, s->gmsh_options);
    } catch (const InvalidArgument& e) {
      r.fail("fibers.data", "is refused: " + s->mesh_file + ": " + e.what());
    }
    (void)mesh;
    return;
  }
  const std::string per = r.string(f, "per", "fibers.per");
  if (per != "element" && per != "node") r.fail("fibers.per", "must be \"element\" or \"node\"");
  const std::filesystem::path dir = std::filesystem::path(s->source).parent_path();
  const std::string path = (dir / r.string(f, "file", "fibers.file")).lexically_normal().string();
  s->fiber_field = read_fiber_file(path, per == "element", mesh);
}

}  // namespace

namespace {

// "clamp" (names of boundary sets: box faces or the mesh file's physical groups) and
// "constraints" ([{"group" or "face": NAME, "components": [...]}]).
// The boundary set `name` of `mesh`, or a failure naming `key` (its message lists the mesh's
// boundary names).
void check_boundary_name(const Reader& r, const Mesh& mesh, const std::string& name,
                         const std::string& key) {
  try {
    mesh.face(name);
  } catch (const InvalidArgument& e) {  // "mesh: unknown boundary face 'x' (expected ...)"
    std::string what = e.what();
    if (what.rfind("mesh: ", 0) == 0) what.erase(0, 6);
    r.fail(key, "is invalid: " + what);
  }
}

void parse_constraints(const Reader& r, const json& doc, const Mesh& mesh, Body* s) {
  if (!doc.contains("clamp") || !doc["clamp"].is_array() || doc["clamp"].empty())
    r.fail("clamp",
           "must be a non-empty array of boundary names (box faces x0, x1, y0, ..., or "
           "a mesh file's physical groups)");
  for (const json& face : doc["clamp"]) {
    if (!face.is_string()) r.fail("clamp", "must hold boundary names as strings");
    check_boundary_name(r, mesh, face.get<std::string>(), "clamp");
    s->constraints.push_back({face.get<std::string>(), {}});
  }
  if (!doc.contains("constraints")) return;
  if (!doc["constraints"].is_array()) r.fail("constraints", "must be an array");
  for (const json& c : doc["constraints"]) {
    r.keys(c, "constraints[]", {"face", "group", "components"});
    const Eigen::VectorXd comps = r.numbers(c, "components", "constraints[].components", 1, 3);
    if (c.contains("face") == c.contains("group"))
      r.fail("constraints[]", "needs one of \"group\" or \"face\" (the same: a boundary name)");
    const char* key = c.contains("group") ? "group" : "face";
    DirichletConstraint dc{r.string(c, key, std::string("constraints[].") + key), {}};
    check_boundary_name(r, mesh, dc.face, std::string("constraints[].") + key);
    for (double k : comps) {
      if (!(k >= 0 && k < s->dim() && k == std::floor(k)))
        r.fail("constraints[].components", "must hold axis indices 0 to " +
                                               std::to_string(s->dim() - 1) + ", got " +
                                               c["components"].dump());
      dc.components.push_back(static_cast<int>(k));
    }
    s->constraints.push_back(dc);
  }
}

/// control.region: one region name or a list of them, each a region of the mesh (a physical
/// volume of a Gmsh file; a box has the one region "body").
std::vector<int> parse_control_regions(const Reader& r, const json& control, const Mesh& mesh) {
  const json& value = control["region"];
  std::vector<std::string> names;
  if (value.is_string()) {
    names.push_back(value.get<std::string>());
  } else if (value.is_array() && !value.empty()) {
    for (const json& v : value) {
      if (!v.is_string()) r.fail("control.region", "must be a region name or a list of names");
      names.push_back(v.get<std::string>());
    }
  } else {
    r.fail("control.region", "must be a region name or a non-empty list of names");
  }
  std::vector<int> regions;
  for (const std::string& name : names) {
    int id = -1;
    try {
      id = mesh.region(name);
    } catch (const InvalidArgument& e) {
      r.fail("control.region", e.what());
    }
    if (std::find(regions.begin(), regions.end(), id) == regions.end()) regions.push_back(id);
  }
  std::sort(regions.begin(), regions.end());
  return regions;
}

void parse_control(const Reader& r, const json& doc, const Mesh& mesh, Body* s) {
  const json& control = r.object(doc, "control", "control");
  r.keys(control, "control", {"space", "region", "lower", "upper", "initial"});
  try {
    s->control_kind = parse_control_kind(r.string(control, "space", "control.space"));
  } catch (const InvalidArgument&) {
    r.fail("control.space", "must be \"vertex\" or \"element\"");
  }
  s->control_lower = r.number(control, "lower", "control.lower");
  s->control_upper = r.number(control, "upper", "control.upper");
  s->control_initial =
      control.contains("initial") ? r.number(control, "initial", "control.initial") : 0.0;
  if (!(s->control_lower <= s->control_upper)) r.fail("control.upper", "must be >= control.lower");
  if (!(s->control_initial >= s->control_lower && s->control_initial <= s->control_upper))
    r.fail("control.initial", "must lie within [control.lower, control.upper] = [" +
                                  std::to_string(s->control_lower) + ", " +
                                  std::to_string(s->control_upper) + "]");
  if (control.contains("region")) s->control_regions = parse_control_regions(r, control, mesh);
  std::vector<int> regions = s->control_regions;  // where the control acts
  if (regions.empty())
    for (int k = 0; k < static_cast<int>(s->materials.size()); ++k) regions.push_back(k);
  for (int k : regions)  // existence needs m < 2a wherever m acts
    if (!(s->control_upper < 2.0 * s->materials[k]->a()))
      r.fail("control.upper",
             "must be < 2a (docs/formulation.md §3.3: existence needs m < 2a)" +
                 (s->materials.size() > 1 ? " in region '" + mesh.region_names[k] + "'"
                                          : std::string()));
}

// The body: mesh, quadrature, materials, fibres, constraints and control, each checked against
// the mesh, so that errors name the file.
void parse_body(const Reader& r, const json& doc, double memory_limit, Body* s) {
  const json& mesh = r.object(doc, "mesh", "mesh");
  const std::string type = r.string(mesh, "type", "mesh.type");
  if (type == "box")
    parse_box_mesh(r, mesh, memory_limit, s);
  else if (type == "gmsh")
    parse_gmsh_mesh(r, mesh, memory_limit, s);
  else
    r.fail("mesh.type", "must be \"box\" or \"gmsh\", got \"" + type + "\"");
  if (mesh.contains("quadrature_degree")) {
    const double q = r.number(mesh, "quadrature_degree", "mesh.quadrature_degree");
    if (!(q >= 1 && q <= 8 && q == std::floor(q)))
      r.fail("mesh.quadrature_degree", "must be an integer from 1 to 8");
    s->quadrature_degree = static_cast<int>(q);
    try {  // a rule that leaves spurious zero-energy modes solves to a wrong state
      check_quadrature_degree(
          s->file_mesh ? s->file_mesh->cell : cell_type(s->dim(), s->order, false),
          s->quadrature_degree);
    } catch (const InvalidArgument& e) {
      r.fail("mesh.quadrature_degree", std::string("is refused: ") + e.what());
    }
  }
  const Mesh body_mesh = s->make_mesh();
  parse_materials(r, doc, body_mesh, s);
  check_scales(r, *s);
  parse_fibers(r, doc, body_mesh, s);
  parse_constraints(r, doc, body_mesh, s);
  parse_control(r, doc, body_mesh, s);
  try {
    make_dof_map(body_mesh, s->constraints);
  } catch (const InvalidArgument& e) {
    r.fail("clamp/constraints", std::string("is invalid: ") + e.what());
  }
  try {  // every connected part held against rigid motions (docs/formulation.md §7)
    check_rigid_motions(body_mesh, s->constraints);
  } catch (const InvalidArgument& e) {
    r.fail("clamp/constraints", std::string("does not hold the body: ") + e.what());
  }
}

}  // namespace

Scene parse_scene(const std::string& text, const std::string& source, double memory_limit) {
  json doc;
  try {
    doc = json::parse(text);
  } catch (const json::exception& e) {  // parse_error, or out_of_range for 1e400
    throw FileError("scene " + source + ": not valid JSON (" + e.what() + ")");
  }
  const Reader r(source);
  if (!doc.is_object()) r.fail("(top level)", "must be an object");
  r.keys(doc, "",
         {"name", "mesh", "material", "materials", "fibers", "clamp", "constraints", "control",
          "target"});
  Scene s;
  s.source = source;
  s.name = doc.contains("name") ? r.string(doc, "name", "name") : default_name(source);
  if (!plain_file_name(s.name))
    r.fail("name",
           "must be a plain file name (letters, digits, '.', '_', '+', '-'; not starting "
           "with '.' or '-'; at most 100 characters): it names the output folder, got " +
               json(s.name).dump());
  s.body.source = source;
  parse_body(r, doc, memory_limit, &s.body);
  if (doc.contains("target")) s.target_json = doc["target"].dump();
  return s;
}

Scene load_scene(const std::string& path, double memory_limit) {
  std::ifstream in(path);
  if (!in) throw FileError("scene " + path + ": cannot open the file");
  std::stringstream ss;
  ss << in.rdbuf();
  return parse_scene(ss.str(), path, memory_limit);
}

}  // namespace softhd

#include "softhd/fe/scene.hpp"

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "softhd/error.hpp"
#include "softhd/fe/newton.hpp"

namespace softhd::fe {

namespace {

using nlohmann::json;

// Reads typed values out of a JSON object, naming the full key in every error.
class Reader {
 public:
  explicit Reader(std::string source) : source_(std::move(source)) {}

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

std::shared_ptr<const Material> read_material(const Reader& r, const json& m, std::string* model) {
  *model = r.string(m, "model", "material.model");
  try {
    if (*model == "mooney_rivlin") {
      return std::make_shared<MooneyRivlin>(r.number(m, "a", "material.a"),
                                            r.number(m, "b", "material.b"),
                                            r.number(m, "c", "material.c"));
    }
    if (*model == "transversely_isotropic") {
      const Eigen::VectorXd f = r.numbers(m, "f", "material.f", 3, 3);
      return std::make_shared<TransverselyIsotropic>(
          r.number(m, "a", "material.a"), r.number(m, "b", "material.b"),
          r.number(m, "c", "material.c"), r.number(m, "d", "material.d"), Eigen::Vector3d(f));
    }
  } catch (const InvalidArgument& e) {
    r.fail("material", std::string("is invalid: ") + e.what());
  }
  r.fail("material.model",
         "must be \"mooney_rivlin\" or \"transversely_isotropic\", got \"" + *model + "\"");
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
  Scene s;
  s.source = source;
  s.name = doc.contains("name") ? r.string(doc, "name", "name") : source;
  const json& mesh = r.object(doc, "mesh", "mesh");
  if (r.string(mesh, "type", "mesh.type") != "box") r.fail("mesh.type", "must be \"box\"");
  s.lower = r.numbers(mesh, "lower", "mesh.lower", 2, 3);
  s.upper = r.numbers(mesh, "upper", "mesh.upper", 2, 3);
  if (s.upper.size() != s.lower.size()) r.fail("mesh.upper", "must have the size of mesh.lower");
  for (int d = 0; d < s.dim(); ++d)
    if (!(s.upper[d] > s.lower[d])) r.fail("mesh.upper", "must be > mesh.lower on every axis");
  const Eigen::VectorXd cells = r.numbers(mesh, "cells", "mesh.cells", s.dim(), s.dim());
  s.cells.resize(s.dim());
  for (int d = 0; d < s.dim(); ++d) {
    if (!(cells[d] >= 1) || cells[d] != std::floor(cells[d]) || cells[d] > 1e6)
      r.fail("mesh.cells", "must hold positive integers, got " + std::to_string(cells[d]));
    s.cells[d] = static_cast<int>(cells[d]);
  }
  const double order = r.number(mesh, "order", "mesh.order");
  if (order != 1 && order != 2) r.fail("mesh.order", "must be 1 or 2");
  s.order = static_cast<int>(order);
  check_mesh_size(box_mesh_size(cells, s.order), memory_limit, "scene " + source + ": the mesh");
  s.material = read_material(r, r.object(doc, "material", "material"), &s.material_model);
  const Eigen::VectorXd f = r.numbers(doc, "fibers", "fibers", 3, 3);
  if (!(f.norm() > 0.0)) r.fail("fibers", "must be a non-zero vector");
  if (s.dim() == 2 && f[2] != 0.0) r.fail("fibers", "must have a zero third component in 2D");
  s.fibers = f.normalized();
  if (!doc.contains("clamp") || !doc["clamp"].is_array() || doc["clamp"].empty())
    r.fail("clamp", "must be a non-empty array of face names (x0, x1, y0, ...)");
  for (const json& face : doc["clamp"]) {
    if (!face.is_string()) r.fail("clamp", "must hold face names as strings");
    s.constraints.push_back({face.get<std::string>(), {}});
  }
  if (doc.contains("constraints")) {
    if (!doc["constraints"].is_array()) r.fail("constraints", "must be an array");
    for (const json& c : doc["constraints"]) {
      const Eigen::VectorXd comps = r.numbers(c, "components", "constraints[].components", 1, 3);
      DirichletConstraint dc{r.string(c, "face", "constraints[].face"), {}};
      for (double k : comps) {
        if (!(k >= 0 && k < s.dim() && k == std::floor(k)))
          r.fail("constraints[].components", "must hold axis indices 0 to " +
                                                 std::to_string(s.dim() - 1) + ", got " +
                                                 c["components"].dump());
        dc.components.push_back(static_cast<int>(k));
      }
      s.constraints.push_back(dc);
    }
  }
  const json& control = r.object(doc, "control", "control");
  try {
    s.control_kind = parse_control_kind(r.string(control, "space", "control.space"));
  } catch (const InvalidArgument&) {
    r.fail("control.space", "must be \"vertex\" or \"element\"");
  }
  s.control_lower = r.number(control, "lower", "control.lower");
  s.control_upper = r.number(control, "upper", "control.upper");
  s.control_initial =
      control.contains("initial") ? r.number(control, "initial", "control.initial") : 0.0;
  if (!(s.control_lower <= s.control_upper)) r.fail("control.upper", "must be >= control.lower");
  if (!(s.control_upper < 2.0 * s.material->a()))
    r.fail("control.upper", "must be < 2a (docs/formulation.md §3.3: existence needs m < 2a)");
  if (doc.contains("target")) s.target_json = doc["target"].dump();
  // Faces and components are checked against the mesh now, so errors name the file.
  try {
    make_dof_map(s.make_mesh(), s.constraints);
  } catch (const InvalidArgument& e) {
    r.fail("clamp/constraints", std::string("is invalid: ") + e.what());
  }
  return s;
}

Scene load_scene(const std::string& path, double memory_limit) {
  std::ifstream in(path);
  if (!in) throw FileError("scene " + path + ": cannot open the file");
  std::stringstream ss;
  ss << in.rdbuf();
  return parse_scene(ss.str(), path, memory_limit);
}

Mesh Scene::make_mesh() const { return make_box_mesh(lower, upper, cells, order); }

Assembler Scene::make_assembler() const {
  return Assembler(make_mesh(), material, fibers, constraints);
}

double Scene::residual_floor() const {
  return fe::residual_floor(material->stiffness_scale(), (upper - lower).prod(), dim());
}

}  // namespace softhd::fe

// Targets described by scene files (moved here from apps/cmd_optimise.cpp so that the CLI and
// the Python module build the same target).

#include "softhd/control/scene_target.hpp"

#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <sstream>

#include "../io/keys.hpp"
#include "softhd/control/targets.hpp"
#include "softhd/error.hpp"
#include "softhd/hausdorff.hpp"
#include "softhd/io/cloud_io.hpp"
#include "softhd/samplers.hpp"

namespace softhd {

namespace {

namespace fs = std::filesystem;

// Counts of the arc target's sampling grid: integers from 1 to 1e6, and a grid whose
// estimated memory (about 100 bytes a point with the distance's trees) fits the limit.
Eigen::Vector3i arc_grid(const fe::Scene& scene, const nlohmann::json& t, double memory_limit) {
  // Default resolution: a cell-centred grid twice as fine as the mesh's nodes.
  Eigen::Vector3i counts = (2 * scene.order * scene.cells).head<3>();
  if (t.contains("cells")) {
    const nlohmann::json& c = t["cells"];
    if (!c.is_array() || c.size() != 3)
      throw InvalidArgument(scene.source + ": target.cells must be an array of 3 integers");
    for (int k = 0; k < 3; ++k) {
      if (!c[k].is_number_integer() || c[k].get<double>() < 1 || c[k].get<double>() > 1e6)
        throw InvalidArgument(scene.source +
                              ": target.cells must hold integers from 1 to 1e6, got " + c.dump());
      counts[k] = c[k].get<int>();
    }
  }
  const double points = double(counts[0]) * counts[1] * counts[2];
  if (points * 100.0 > memory_limit)
    throw ResourceError(
        scene.source + ": target.cells asks for " + std::to_string(points) + " points, about " +
        std::to_string(points * 100.0 / (1u << 30)) + " GiB, above the memory limit of " +
        std::to_string(memory_limit / (1u << 30)) + " GiB (raise the limit: --max-memory GIB)");
  return counts;
}

SceneTarget arc_target(const fe::Scene& scene, const fe::Mesh& mesh, const nlohmann::json& t,
                       double memory_limit) {
  if (scene.dim() != 3 || !scene.is_box())
    throw InvalidArgument(scene.source + ": target.kind arc needs a 3D box body (mesh.type box)");
  double angle = ArcMap().angle;
  if (t.contains("angle")) {
    if (!t["angle"].is_number())
      throw InvalidArgument(scene.source + ": target.angle must be a number (radians)");
    angle = t["angle"].get<double>();
  }
  const ArcMap T = arc_map(scene, angle);
  const Eigen::Vector3i counts = arc_grid(scene, t, memory_limit);
  const PointCloud grid = sample_box_grid(scene.lower, scene.upper, counts);
  std::ostringstream d;
  d << "arc of " << T.angle * 180.0 / M_PI << " degrees, " << counts[0] << "x" << counts[1] << "x"
    << counts[2] << " cell-centred grid";
  return {T.apply(grid), T.displacement(mesh), d.str()};
}

SceneTarget cloud_target(const fe::Scene& scene, const fe::Mesh& mesh, const nlohmann::json& t,
                         double memory_limit) {
  if (!t.contains("file") || !t["file"].is_string())
    throw InvalidArgument(scene.source + ": target.file must be a path string");
  const fs::path dir = fs::path(scene.source).parent_path();
  const fs::path f = (dir / t["file"].get<std::string>()).lexically_normal();
  PointCloud cloud = read_cloud(f.string(), scene.dim());
  check_coordinates(cloud, f.string());
  if (!t.contains("solved_on")) return {cloud, std::nullopt, "cloud file " + f.string()};
  // A manufactured target: the deformed nodes of a state solved on another scene's mesh.
  if (!t["solved_on"].is_string())
    throw InvalidArgument(scene.source + ": target.solved_on must be a scene path string");
  const fs::path source = (dir / t["solved_on"].get<std::string>()).lexically_normal();
  const NodalMap T(fe::load_scene(source.string(), memory_limit).make_mesh(), cloud);
  return {cloud, T.displacement(mesh),
          "cloud file " + f.string() + " (deformed nodes of " + source.string() + ")"};
}

// The keys both kinds take: "surface" (a boolean) and "camera" (3 finite numbers), 3D only.
void read_view_keys(const fe::Scene& scene, const nlohmann::json& t, SceneTarget* target) {
  if ((t.contains("surface") || t.contains("camera")) && scene.dim() != 3)
    throw InvalidArgument(scene.source + ": target.surface and target.camera need a 3D body");
  if (t.contains("surface")) {
    if (!t["surface"].is_boolean())
      throw InvalidArgument(scene.source + ": target.surface must be true or false");
    target->surface = t["surface"].get<bool>();
  }
  if (t.contains("camera")) {
    const nlohmann::json& c = t["camera"];
    if (!c.is_array() || c.size() != 3 || !c[0].is_number() || !c[1].is_number() ||
        !c[2].is_number())
      throw InvalidArgument(scene.source +
                            ": target.camera must be an array of 3 numbers (the body's frame)");
    target->camera = Eigen::Vector3d(c[0].get<double>(), c[1].get<double>(), c[2].get<double>());
    if (!target->camera->allFinite())
      throw InvalidArgument(scene.source + ": target.camera must be finite");
  }
}

}  // namespace

void apply_target_settings(const SceneTarget& target, ShapeObjectiveOptions* options) {
  if (target.surface) {
    options->particles = Particles::boundary;
    options->volumes = ParticleVolumes::deformed;
  }
  if (target.camera) {
    options->form.sides = Sides::visible;
    options->camera = target.camera;
  }
}

ArcMap arc_map(const fe::Scene& scene, double angle) {
  if (scene.dim() != 3) throw InvalidArgument(scene.source + ": an arc map needs a 3D body");
  ArcMap T;
  T.length = scene.upper[0] - scene.lower[0];
  T.thickness = scene.upper[2] - scene.lower[2];
  T.angle = angle;
  T.origin = scene.lower.head<3>();  // the arc of the plate where the scene puts it
  T.validate();
  return T;
}

SceneTarget scene_target(const fe::Scene& scene, const fe::Mesh& mesh, double memory_limit) {
  if (scene.target_json.empty())
    throw InvalidArgument(scene.source + ": the scene has no \"target\"; give a target cloud");
  const nlohmann::json t = nlohmann::json::parse(scene.target_json);
  if (!t.is_object())
    throw InvalidArgument(scene.source + ": key 'target' must be an object, got " + t.dump());
  if (!t.contains("kind") || !t["kind"].is_string())
    throw InvalidArgument(scene.source + ": target.kind must be \"arc\" or \"cloud\"");
  const std::string kind = t["kind"].get<std::string>();
  const std::string where = "scene " + scene.source;
  if (kind == "arc" || kind == "cloud") {
    if (kind == "arc")
      io::check_keys(t, where, "target", {"kind", "angle", "cells", "surface", "camera"});
    if (kind == "cloud")
      io::check_keys(t, where, "target", {"kind", "file", "solved_on", "surface", "camera"});
    SceneTarget target = kind == "arc" ? arc_target(scene, mesh, t, memory_limit)
                                       : cloud_target(scene, mesh, t, memory_limit);
    read_view_keys(scene, t, &target);
    return target;
  }
  throw InvalidArgument(scene.source + ": target.kind must be \"arc\" or \"cloud\", got \"" + kind +
                        "\"");
}

SceneTarget file_target(const std::string& path, int dim) {
  PointCloud cloud = read_cloud(path, dim);
  check_coordinates(cloud, path);
  if (dim != 0 && cloud.dim() != dim)
    throw InvalidArgument("the target cloud '" + path + "' is " + std::to_string(cloud.dim()) +
                          "D but the scene's body is " + std::to_string(dim) + "D");
  return {std::move(cloud), std::nullopt, "cloud file " + path};
}

}  // namespace softhd

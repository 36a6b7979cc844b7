// Targets described by scene files (moved here from apps/cmd_optimise.cpp so that the CLI and
// the Python module build the same target).

#include "softhd/control/scene_target.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <sstream>

#include "../common/decimal.hpp"
#include "../common/keys.hpp"
#include "softhd/control/pose_file.hpp"
#include "softhd/control/shape_objective.hpp"
#include "softhd/control/shape_tracking.hpp"
#include "softhd/control/targets.hpp"
#include "softhd/error.hpp"
#include "softhd/fe/boundary.hpp"
#include "softhd/fe/cloud.hpp"
#include "softhd/hausdorff.hpp"
#include "softhd/io/cloud_io.hpp"
#include "softhd/samplers.hpp"
#include "softhd/scan/cleanup.hpp"
#include "softhd/scan/surface_weights.hpp"

namespace softhd {

namespace {

namespace fs = std::filesystem;
using detail::decimal;

// Counts of the arc target's sampling grid: integers from 1 to 1e6, and a grid whose
// estimated memory (about 100 bytes a point with the distance's trees) fits the limit.
Eigen::Vector3i arc_grid(const Scene& scene, const nlohmann::json& t, double memory_limit) {
  // Default resolution: a cell-centred grid twice as fine as the mesh's nodes.
  Eigen::Vector3i counts = (2 * scene.body.order * scene.body.cells).head<3>();
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

SceneTarget arc_target(const Scene& scene, const fe::Mesh& mesh, const nlohmann::json& t,
                       double memory_limit) {
  if (scene.body.dim() != 3 || !scene.body.is_box())
    throw InvalidArgument(scene.source + ": target.kind arc needs a 3D box body (mesh.type box)");
  double angle = ArcMap().angle;
  if (t.contains("angle")) {
    if (!t["angle"].is_number())
      throw InvalidArgument(scene.source + ": target.angle must be a number (radians)");
    angle = t["angle"].get<double>();
  }
  const ArcMap T = arc_map(scene, angle);
  const Eigen::Vector3i counts = arc_grid(scene, t, memory_limit);
  const PointCloud grid = sample_box_grid(scene.body.lower, scene.body.upper, counts);
  std::ostringstream d;
  d << "arc of " << T.angle * 180.0 / M_PI << " degrees, " << counts[0] << "x" << counts[1] << "x"
    << counts[2] << " cell-centred grid";
  SceneTarget target{T.apply(grid), T.displacement(mesh), d.str(), {}};
  // Its cells: the grid's hexahedra (the samples are their centres), nodes mapped by T.
  fe::Mesh cells = fe::make_box_mesh(scene.body.lower, scene.body.upper, counts, 1);
  for (Eigen::Index i = 0; i < cells.num_nodes(); ++i)
    cells.nodes.row(i) = T(cells.nodes.row(i).transpose()).transpose();
  target.cells = std::move(cells);
  return target;
}

// A number at key `key` of `o` (the block `path` of the target), or InvalidArgument.
double number_at(const Scene& scene, const nlohmann::json& o, const char* path, const char* key,
                 const char* what) {
  if (!o[key].is_number())
    throw InvalidArgument(scene.source + ": target." + path + key + " must be " + what + ", got " +
                          o[key].dump());
  return o[key].get<double>();
}

// target.clean: {"crop": MARGIN, "plane": DIST, "outliers": {"k": K, "ratio": R}}, each optional.
scan::ScanCleanup parse_clean(const Scene& scene, const nlohmann::json& t) {
  scan::ScanCleanup c;
  if (!t.contains("clean")) return c;
  const nlohmann::json& j = t["clean"];
  if (!j.is_object())
    throw InvalidArgument(scene.source + ": target.clean must be an object, got " + j.dump());
  const std::string where = "scene " + scene.source;
  io::check_keys(j, where, "target.clean", {"crop", "plane", "outliers"});
  if (j.contains("crop")) c.crop = number_at(scene, j, "clean.", "crop", "a margin >= 0");
  if (j.contains("plane")) c.plane = number_at(scene, j, "clean.", "plane", "a distance > 0");
  if (j.contains("outliers")) {
    const nlohmann::json& o = j["outliers"];
    if (!o.is_object())
      throw InvalidArgument(scene.source + ": target.clean.outliers must be an object {\"k\": " +
                            "K, \"ratio\": R}, got " + o.dump());
    io::check_keys(o, where, "target.clean.outliers", {"k", "ratio"});
    scan::ScanCleanup::Outliers out;
    if (o.contains("k")) {
      if (!o["k"].is_number_integer() || o["k"].get<double>() < 1 || o["k"].get<double>() > 1e4)
        throw InvalidArgument(scene.source +
                              ": target.clean.outliers.k must be an integer from 1 to 10000, got " +
                              o["k"].dump());
      out.k = o["k"].get<int>();
    }
    if (o.contains("ratio"))
      out.ratio = number_at(scene, o, "clean.outliers.", "ratio", "a number");
    c.outliers = out;
  }
  try {
    c.validate();
  } catch (const InvalidArgument& e) {
    throw InvalidArgument(scene.source + ": target." + e.what());
  }
  return c;
}

// target.weights: "file" (as read), "knn" or "delaunay" (scan::AreaEstimate).
std::optional<scan::AreaEstimate> parse_weights(const Scene& scene, const nlohmann::json& t) {
  if (!t.contains("weights")) return std::nullopt;
  const std::string name = t["weights"].is_string() ? t["weights"].get<std::string>() : "";
  if (name == "file") return std::nullopt;
  if (name != "knn" && name != "delaunay")
    throw InvalidArgument(scene.source +
                          ": target.weights must be \"file\", \"knn\" or \"delaunay\", got " +
                          t["weights"].dump());
  return scan::area_estimate_from_string(name);
}

// read → crop (to the body's box, inflated) → plane → outliers → weights; what each step
// did and what the reader skipped go into `description`.
// With "fixture" (and no "pose"): the table, the plane the clean-up's plane step removes, into
// *table (refused if it holds under min_fraction of the points: no table to hold the pose on).
PointCloud read_scan(const Scene& scene, const nlohmann::json& t, const std::string& file,
                     std::string& description, std::optional<scan::Plane>* table) {
  std::vector<std::string> notes;
  PointCloud cloud = read_cloud(file, scene.body.dim(), &notes);
  check_coordinates(cloud, file);
  const scan::ScanCleanup clean = parse_clean(scene, t);
  if (t.contains("fixture") && !t.contains("pose") && clean.plane && cloud.dim() == 3) {
    scan::PlaneRemoval removal;  // as clean_scan's plane step (no crop in the camera's frame)
    removal.distance = *clean.plane;
    const scan::Plane plane = scan::find_dominant_plane(cloud, removal);
    if (static_cast<double>(plane.inliers) <
        removal.min_fraction * static_cast<double>(cloud.size()))
      throw InvalidArgument(scene.source + ": target.fixture: no table plane in " + file +
                            " within target.clean.plane " + decimal(*clean.plane) +
                            ": the largest plane holds " + std::to_string(plane.inliers) + " of " +
                            std::to_string(cloud.size()) + " points (fewer than 10 %)");
    *table = plane;
  }
  const std::optional<scan::AreaEstimate> weights = parse_weights(scene, t);
  std::vector<scan::CleanupStep> steps;
  const Eigen::Index read = cloud.size();
  try {
    cloud = scan::clean_scan(cloud, scene.body.lower, scene.body.upper, clean, &steps);
    if (weights) cloud = scan::with_area_weights(cloud, *weights);
  } catch (const InvalidArgument& e) {
    throw InvalidArgument(scene.source + ": target " + file + ": " + e.what());
  }
  if (!steps.empty()) description += "; " + scan::describe(steps, read);
  if (weights) description += "; weights " + scan::to_string(*weights);
  for (const std::string& n : notes) description += "; " + n;
  return cloud;
}

SceneTarget cloud_target(const Scene& scene, const fe::Mesh& mesh, const nlohmann::json& t,
                         double memory_limit, std::optional<scan::Plane>* table) {
  if (!t.contains("file") || !t["file"].is_string())
    throw InvalidArgument(scene.source + ": target.file must be a path string");
  const fs::path dir = fs::path(scene.source).parent_path();
  const fs::path f = (dir / t["file"].get<std::string>()).lexically_normal();
  std::string description = "cloud file " + f.string();
  const PointCloud cloud = read_scan(scene, t, f.string(), description, table);
  if (!t.contains("solved_on")) return {cloud, std::nullopt, description, {}};
  if (t.contains("clean") || t.contains("weights"))
    throw InvalidArgument(scene.source +
                          ": target.solved_on takes the file's nodes as they are: no clean or "
                          "weights with it");
  // A manufactured target: the deformed nodes of a state solved on another scene's mesh.
  if (!t["solved_on"].is_string())
    throw InvalidArgument(scene.source + ": target.solved_on must be a scene path string");
  const fs::path source = (dir / t["solved_on"].get<std::string>()).lexically_normal();
  const NodalMap T(load_scene(source.string(), memory_limit).body.make_mesh(), cloud);
  SceneTarget target{cloud,
                     T.displacement(mesh),
                     "cloud file " + f.string() + " (deformed nodes of " + source.string() + ")",
                     {}};
  target.cells = T.source();  // its cells at the file's nodes
  target.cells->nodes = cloud.points();
  return target;
}

// A number at key `key` of the target block, finite (and > 0 if `positive`).
double target_number(const Scene& scene, const nlohmann::json& v, const std::string& key,
                     bool positive) {
  if (!v.is_number() || !std::isfinite(v.get<double>()) || (positive && !(v.get<double>() > 0.0)))
    throw InvalidArgument(scene.source + ": target." + key + " must be a number" +
                          (positive ? " > 0" : "") + ", got " + v.dump());
  return v.get<double>();
}

// The keys "distance", "cap", "cap_q" of a target block (docs/guide.md); "visible" goes with
// "camera", which implies it when "distance" is absent.
TargetDistance target_distance(const Scene& scene, const nlohmann::json& t, bool camera_frame) {
  TargetDistance d;
  const bool camera = t.contains("camera") || camera_frame;  // a pose gives the camera
  const bool implied = t.contains("camera");
  if (implied) d.sides = Sides::visible;
  if (t.contains("distance")) {
    const nlohmann::json& v = t["distance"];
    const std::string name = v.is_string() ? v.get<std::string>() : v.dump();
    if (name == "visible" && !camera)
      throw InvalidArgument(scene.source +
                            ": target.distance \"visible\" needs the camera's position: give "
                            "target.camera [x, y, z] in the body's frame");
    if (!v.is_string() || (name != "symmetric" && name != "scan_to_body" && name != "visible"))
      throw InvalidArgument(scene.source +
                            ": target.distance must be \"symmetric\", \"scan_to_body\" or "
                            "\"visible\", got " +
                            v.dump());
    if (implied && name != "visible")
      throw InvalidArgument(scene.source + ": target.camera is given but target.distance is \"" +
                            name + "\" (a camera is for the visible distance)");
    d.sides = sides_from_string(name);
  }
  if (t.contains("cap")) {
    const nlohmann::json& c = t["cap"];
    if (c.is_object()) {
      io::check_keys(c, "scene " + scene.source, "target.cap", {"quantile", "factor"});
      if (!c.contains("quantile") || !c.contains("factor"))
        throw InvalidArgument(scene.source + ": target.cap needs both \"quantile\" and \"factor\"");
      d.cap_quantile = target_number(scene, c["quantile"], "cap.quantile", false);
      d.cap_factor = target_number(scene, c["factor"], "cap.factor", true);
      if (!(d.cap_quantile >= 0.0 && d.cap_quantile <= 1.0))
        throw InvalidArgument(scene.source + ": target.cap.quantile must be in [0, 1], got " +
                              c["quantile"].dump());
    } else {
      d.cap = target_number(scene, c, "cap", true);
    }
  }
  if (t.contains("cap_q")) d.cap_q = target_number(scene, t["cap_q"], "cap_q", true);
  if (!(d.cap_q >= SoftCap::kMinQ))
    throw InvalidArgument(scene.source + ": target.cap_q must be >= 0.001 (the soft cap's " +
                          "sharpness; below it the cap cannot be evaluated accurately), got " +
                          t["cap_q"].dump());
  return d;
}

// The keys both kinds take: "surface" (a boolean) and "camera" (3 finite numbers), 3D only.
void read_view_keys(const Scene& scene, const nlohmann::json& t, SceneTarget* target) {
  if ((t.contains("surface") || t.contains("camera")) && scene.body.dim() != 3)
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

// The keys "frame", "align", "pose" of a cloud target (docs/guide.md).
struct FrameKeys {
  TargetFrame frame = TargetFrame::body;
  scan::PoseKind align = scan::PoseKind::rigid;
  std::optional<scan::Pose> pose;
  std::optional<PoseBound> uncertainty;
  std::optional<scan::Fixture> fixture;
  std::string description;
};

// "fixture": {"normal": [n1, n2, n3], "offset": d}, the table n·x = d in the body's frame; without
// "pose" the table is found in the scan by "clean": {"plane": D}, which must be given.
scan::Fixture read_fixture(const Scene& scene, const nlohmann::json& t, scan::PoseKind kind) {
  const nlohmann::json& j = t["fixture"];
  const std::string key = scene.source + ": target.fixture";
  if (!j.is_object())
    throw InvalidArgument(key + " must be {\"normal\": [n1, n2, n3], \"offset\": d}, got " +
                          j.dump());
  io::check_keys(j, "scene " + scene.source, "target.fixture",
                 {"normal", "offset", "clamp", "clamp_seen"});
  scan::Fixture f;
  const nlohmann::json n = j.contains("normal") ? j["normal"] : nlohmann::json();
  if (!n.is_array() || n.size() != 3 ||
      !std::all_of(n.begin(), n.end(), [](const nlohmann::json& v) { return v.is_number(); }))
    throw InvalidArgument(key + ".normal must be 3 numbers, got " + n.dump());
  for (int k = 0; k < 3; ++k) f.normal[k] = n[static_cast<size_t>(k)].get<double>();
  for (const char* name : {"clamp", "clamp_seen"}) {
    if (!j.contains(name)) continue;
    const nlohmann::json& c = j[name];
    if (!c.is_array() || c.size() != 3 ||
        !std::all_of(c.begin(), c.end(), [](const nlohmann::json& v) { return v.is_number(); }))
      throw InvalidArgument(key + "." + name + " must be 3 numbers, got " + c.dump());
    Eigen::Vector3d& d = std::string(name) == "clamp" ? f.clamp : f.clamp_seen;
    for (int k = 0; k < 3; ++k) d[k] = c[static_cast<size_t>(k)].get<double>();
  }
  const nlohmann::json d = j.contains("offset") ? j["offset"] : nlohmann::json();
  if (!d.is_number()) throw InvalidArgument(key + ".offset must be a number, got " + d.dump());
  f.offset = d.get<double>();
  try {
    f.validate();
  } catch (const InvalidArgument& e) {
    throw InvalidArgument(scene.source + ": target." + e.what());
  }
  if (kind != scan::PoseKind::rigid)
    throw InvalidArgument(key +
                          " needs \"align\": \"rigid\" (a scale would change the table's "
                          "height)");
  const bool plane = t.contains("clean") && t["clean"].is_object() && t["clean"].contains("plane");
  if (!t.contains("pose") && !plane)
    throw InvalidArgument(key +
                          " needs the table found in the scan: give \"clean\": {\"plane\": "
                          "D} (or a \"pose\" whose tilt and height it keeps)");
  return f;
}

// A rigid start pose has scale 1; a similarity's lies within the pose bounds (PoseBounds).
void check_start_scale(const Scene& scene, const scan::Pose& pose, scan::PoseKind kind,
                       const std::string& file) {
  const PoseBounds bounds;
  const bool rigid = kind == scan::PoseKind::rigid;
  if (rigid ? pose.rigid() : pose.s >= bounds.scale_min && pose.s <= bounds.scale_max) return;
  const std::string head =
      scene.source + ": target.pose: the pose in '" + file + "' has scale " + decimal(pose.s);
  if (rigid)
    throw InvalidArgument(head + ", but a rigid pose (target.align \"rigid\") has scale 1 (to " +
                          decimal(scan::Pose::kScaleTolerance) +
                          "); give \"align\": \"similarity\" or a rigid pose");
  throw InvalidArgument(head + ", outside the similarity's scale bounds [" +
                        decimal(bounds.scale_min) + ", " + decimal(bounds.scale_max) + "]");
}

// "pose_uncertainty": {"degrees": A, "length": D}, both finite and > 0, as a PoseBound.
PoseBound read_uncertainty(const Scene& scene, const nlohmann::json& t) {
  const nlohmann::json& u = t["pose_uncertainty"];
  const std::string key = scene.source + ": target.pose_uncertainty";
  if (!u.is_object())
    throw InvalidArgument(key + " must be {\"degrees\": A, \"length\": D}, got " + u.dump());
  io::check_keys(u, "scene " + scene.source, "target.pose_uncertainty", {"degrees", "length"});
  double value[2] = {0.0, 0.0};
  const char* names[2] = {"degrees", "length"};
  for (int k = 0; k < 2; ++k) {
    const nlohmann::json& v = u.contains(names[k]) ? u[names[k]] : nlohmann::json();
    if (!v.is_number() || !std::isfinite(v.get<double>()) || !(v.get<double>() > 0.0))
      throw InvalidArgument(key + "." + names[k] + " must be a number > 0, got " + v.dump());
    value[k] = v.get<double>();
  }
  return PoseBound{value[0] * M_PI / 180.0, value[1]};
}

FrameKeys read_frame_keys(const Scene& scene, const nlohmann::json& t) {
  FrameKeys keys;
  FrameKeys* target = &keys;
  if (t.contains("frame")) {
    const nlohmann::json& f = t["frame"];
    const std::string name = f.is_string() ? f.get<std::string>() : "";
    if (name != "body" && name != "camera")
      throw InvalidArgument(scene.source + ": target.frame must be \"body\" or \"camera\", got " +
                            f.dump());
    target->frame = name == "camera" ? TargetFrame::camera : TargetFrame::body;
  }
  const bool camera = target->frame == TargetFrame::camera;
  for (const char* key : {"align", "pose", "pose_uncertainty", "fixture"})
    if (t.contains(key) && !camera)
      throw InvalidArgument(scene.source + ": target." + key +
                            " is for a cloud in the camera's frame (give \"frame\": \"camera\")");
  if (!camera) return keys;
  if (scene.body.dim() != 3)
    throw InvalidArgument(scene.source + ": target.frame \"camera\" needs a 3D body");
  if (t.contains("camera"))
    throw InvalidArgument(scene.source +
                          ": target.camera: with \"frame\": \"camera\" the camera is the pose's "
                          "(remove target.camera)");
  if (t.contains("clean") && t["clean"].is_object() && t["clean"].contains("crop"))
    throw InvalidArgument(scene.source +
                          ": target.clean.crop crops to the body's box, which is not in the "
                          "camera's frame (remove it with \"frame\": \"camera\")");
  if (t.contains("align")) {
    const nlohmann::json& a = t["align"];
    const std::string name = a.is_string() ? a.get<std::string>() : "";
    if (name != "rigid" && name != "similarity")
      throw InvalidArgument(scene.source +
                            ": target.align must be \"rigid\" or \"similarity\", got " + a.dump());
    target->align = scan::pose_kind_from_string(name);
  }
  if (t.contains("pose")) {
    if (!t["pose"].is_string())
      throw InvalidArgument(scene.source + ": target.pose must be a pose file path string, got " +
                            t["pose"].dump());
    const fs::path dir = fs::path(scene.source).parent_path();
    const fs::path f = (dir / t["pose"].get<std::string>()).lexically_normal();
    if (!fs::exists(f))
      throw FileError(scene.source + ": target.pose: cannot open the pose file '" + f.string() +
                      "'");
    target->pose = read_pose(f.string());
    check_start_scale(scene, *target->pose, target->align, f.string());
    target->description += "; camera frame, start pose " + f.string();
    if (t.contains("pose_uncertainty")) target->uncertainty = read_uncertainty(scene, t);
  } else {
    if (t.contains("pose_uncertainty"))
      throw InvalidArgument(scene.source +
                            ": target.pose_uncertainty is the uncertainty of target.pose (give "
                            "\"pose\": FILE)");
    target->description += "; camera frame, start pose by align";
  }
  if (t.contains("fixture")) {
    target->fixture = read_fixture(scene, t, target->align);
    target->description += "; the fixture's table";
  }
  return keys;
}

}  // namespace

std::string to_string(TargetFrame frame) {
  return frame == TargetFrame::camera ? "camera" : "body";
}

scan::Pose start_pose(const SceneTarget& target, const fe::Assembler& assembler,
                      const ShapeObjectiveOptions& options, int threads) {
  if (target.frame != TargetFrame::camera)
    throw InvalidArgument("start_pose: the target is in the body's frame (no pose to find)");
  if (target.pose) return *target.pose;
  const Eigen::VectorXd rest = Eigen::VectorXd::Zero(assembler.dofs().num_dofs);
  const PointCloud body =
      options.particles == Particles::boundary
          ? fe::boundary_cloud(assembler.mesh(), fe::boundary_facets(assembler.mesh()), rest,
                               fe::CloudVolumes::kReference)
          : fe::deformed_cloud(assembler, rest, fe::CloudPoints::kNodes,
                               fe::CloudVolumes::kReference);
  scan::AlignOptions a;
  a.kind = target.align;
  a.form.sides = target.distance.sides == Sides::symmetric ? Sides::symmetric : Sides::scan_to_body;
  a.threads = threads;
  a.fixture = target.fixture;
  a.table = target.table;
  return scan::align(body, target.cloud, a).pose;
}

void apply_target_settings(const SceneTarget& target, ShapeObjectiveOptions* options) {
  if (target.surface) {
    options->particles = Particles::boundary;
    options->volumes = ParticleVolumes::deformed;
  }
  if (target.camera) {
    options->form.sides = Sides::visible;
    options->camera = target.camera;
  }
  if (target.frame == TargetFrame::camera) options->pose_kind = target.align;
  options->pose_bound = target.pose_uncertainty;
  if (target.fixture) options->pose_table_normal = target.fixture->normal;
}

DistanceForm target_form(const TargetDistance& distance, const ShapeObjective& objective) {
  DistanceForm form;
  form.sides = distance.sides;
  form.cap.c = distance.cap;
  form.cap.q = distance.cap_q;
  if (distance.cap_factor > 0.0) {
    const Eigen::VectorXd rest =
        Eigen::VectorXd::Zero(objective.state_path().last_state().u.size());
    form.cap.c = cap_from_quantile(objective.fields(rest).field_target, distance.cap_quantile,
                                   distance.cap_factor);
  }
  return form;
}

ArcMap arc_map(const Scene& scene, double angle) {
  if (scene.body.dim() != 3) throw InvalidArgument(scene.source + ": an arc map needs a 3D body");
  ArcMap T;
  T.length = scene.body.upper[0] - scene.body.lower[0];
  T.thickness = scene.body.upper[2] - scene.body.lower[2];
  T.angle = angle;
  T.origin = scene.body.lower.head<3>();  // the arc of the plate where the scene puts it
  T.validate();
  return T;
}

SceneTarget scene_target(const Scene& scene, const fe::Mesh& mesh, double memory_limit) {
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
      io::check_keys(t, where, "target",
                     {"kind", "angle", "cells", "distance", "cap", "cap_q", "surface", "camera",
                      "quadrature"});
    if (kind == "cloud")
      io::check_keys(t, where, "target",
                     {"kind", "file", "solved_on", "clean", "weights", "distance", "cap", "cap_q",
                      "quadrature", "surface", "camera", "frame", "align", "pose",
                      "pose_uncertainty", "fixture"});
    // The frame's keys before the scan is read and cleaned.
    const FrameKeys frame = kind == "cloud" ? read_frame_keys(scene, t) : FrameKeys{};
    std::optional<scan::Plane> table;
    SceneTarget st = kind == "arc" ? arc_target(scene, mesh, t, memory_limit)
                                   : cloud_target(scene, mesh, t, memory_limit, &table);
    st.frame = frame.frame;
    st.align = frame.align;
    st.pose = frame.pose;
    st.pose_uncertainty = frame.uncertainty;
    st.fixture = frame.fixture;
    st.table = table;
    st.description += frame.description;
    st.distance = target_distance(scene, t, st.frame == TargetFrame::camera);
    read_view_keys(scene, t, &st);
    if (t.contains("quadrature")) {
      const nlohmann::json& q = t["quadrature"];
      if (!q.is_string() || (q != "collocation" && q != "cells"))
        throw InvalidArgument(scene.source +
                              ": target.quadrature must be \"collocation\" or \"cells\", got " +
                              q.dump());
      st.quadrature = quadrature_from_string(q.get<std::string>());
    }
    return st;
  }
  throw InvalidArgument(scene.source + ": target.kind must be \"arc\" or \"cloud\", got \"" + kind +
                        "\"");
}

SceneTarget file_target(const std::string& path, int dim) {
  std::vector<std::string> notes;
  PointCloud cloud = read_cloud(path, dim, &notes);
  check_coordinates(cloud, path);
  if (dim != 0 && cloud.dim() != dim)
    throw InvalidArgument("the target cloud '" + path + "' is " + std::to_string(cloud.dim()) +
                          "D but the scene's body is " + std::to_string(dim) + "D");
  std::string description = "cloud file " + path;
  for (const std::string& n : notes) description += "; " + n;
  return {std::move(cloud), std::nullopt, description, {}};
}

}  // namespace softhd

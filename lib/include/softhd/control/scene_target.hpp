#pragma once
/// \file scene_target.hpp
/// The target cloud a scene file describes (its "target" object, docs/guide.md), with the
/// known map T where there is one (docs/formulation.md §5.2). `softhd optimise` and the Python
/// module `softhd.optimise` both build their target here.
///
///     {"kind": "arc", "angle": RAD [, "cells": [n1, n2, n3]]}   the plate bent into an arc,
///         sampled on a cell-centred grid (default: twice as fine as the mesh's nodes)
///     {"kind": "cloud", "file": PATH [, "solved_on": SCENE]}     a cloud file (relative to the
///         scene file); with solved_on it holds the deformed nodes of a state solved on SCENE's
///         mesh, which gives the known map
///     {"kind": "cloud", "file": PATH, "clean": {"crop": MARGIN, "plane": DIST,
///      "outliers": {"k": K, "ratio": R}}, "weights": "file"|"knn"|"delaunay"}   a scan: read,
///         cropped to the body's box inflated by MARGIN × its diagonal, its dominant plane
///         removed, statistical outliers removed, area weights estimated (scan/cleanup.hpp,
///         scan/surface_weights.hpp; each optional); the description says what each removed
///
/// Either kind also takes the distance's form (docs/formulation.md §8, docs/guide.md):
///     "distance": "symmetric" | "scan_to_body" | "visible"   (visible needs "camera")
///     "cap": C  or  "cap": {"quantile": Q, "factor": F}   the soft cap c, fixed or
///         F × the Q-quantile of d̃_X(y_j) at the start (cap_from_quantile)
///     "cap_q": Q                                   the cap's sharpness (default 4)
/// and, 3D only, "surface": true (a surface scan: the moving cloud is the body's boundary with
/// its current facet areas, §8.6) and "camera": [x, y, z] (the camera in the body's frame, for
/// the visible distance, which it implies when "distance" is absent, §8.7).
///
/// A cloud target in the camera's frame (3D; docs/formulation.md §8.10): the pose is refined
/// jointly with the control,
///     "frame": "body" | "camera"      the frame of the cloud (default body)
///     "align": "rigid" | "similarity"  camera frame only: what the pose may change (default rigid)
///     "pose": FILE                     camera frame only: the start pose (a pose file of
///         `softhd align`, scan → body, relative to the scene file); without it the start is
///         scan::align against the body at rest
///     "pose_uncertainty": {"degrees": A, "length": D}   with "pose": its uncertainty, a bound
///         on the pose found by projection (|ω| ≤ A degrees, |v| ≤ D, §8.11)
/// With "frame": "camera" the camera of the visible distance is the pose's (no "camera" key), and
/// "clean.crop" is refused (the body's box is in the body's frame).

#include <Eigen/Core>
#include <optional>
#include <string>

#include "softhd/control/scene.hpp"
#include "softhd/control/shape_objective.hpp"
#include "softhd/control/targets.hpp"
#include "softhd/fe/mesh.hpp"
#include "softhd/hausdorff.hpp"
#include "softhd/point_cloud.hpp"
#include "softhd/scan/align.hpp"
#include "softhd/scan/fixture.hpp"
#include "softhd/scan/pose.hpp"

namespace softhd {

/// The distance's form a target block asks for (its keys "distance", "cap", "cap_q").
struct TargetDistance {
  Sides sides = Sides::symmetric;  ///< symmetric, scan_to_body, or visible (with a camera)
  double cap = 0.0;                ///< a fixed cap c (0: none, unless the quantile rule is set)
  /// The rule c = cap_factor × the cap_quantile-quantile of d̃_X(y_j) at the start; used
  /// when cap_factor > 0 (then `cap` is 0).
  double cap_quantile = 0.0;  ///< Q of the rule, in (0, 1]
  double cap_factor = 0.0;    ///< F of the rule (> 0 when the rule is used)
  double cap_q = 4.0;         ///< the cap's sharpness q
};

/// The frame of a target's cloud: the body's (default) or the camera's (the pose found jointly).
enum class TargetFrame { body, camera };
/// "body" or "camera".
std::string to_string(TargetFrame frame);

/// A target cloud and, if T is known, the nodal displacements u_T = T(X) − X of the body.
struct SceneTarget {
  PointCloud cloud;                                 ///< Ω_d
  std::optional<Eigen::VectorXd> map_displacement;  ///< u_T at `mesh`'s nodes, if T is known
  std::string description;                          ///< one line for people
  TargetDistance distance;                          ///< the form its block asks for
  bool surface = false;                             ///< "surface": the moving cloud is the boundary
  std::optional<Eigen::Vector3d> camera = std::nullopt;  ///< "camera": visible from there
  TargetFrame frame = TargetFrame::body;                 ///< "frame"
  scan::PoseKind align = scan::PoseKind::rigid;          ///< "align" (camera frame)
  std::optional<scan::Pose> pose = std::nullopt;         ///< "pose": the start (camera frame)
  /// "pose_uncertainty": {"degrees", "length"} of "pose" (the projection's PoseBound).
  std::optional<PoseBound> pose_uncertainty = std::nullopt;
  /// "fixture": {"normal", "offset"}, the table in the body's frame (docs/formulation.md
  /// §8.12): the start pose by align keeps it on `table`, and the projection's pose keeps the
  /// start's tilt and height.
  std::optional<scan::Fixture> fixture = std::nullopt;
  /// The table found in the scan by "clean": {"plane": D} (its frame), with "fixture".
  std::optional<scan::Plane> table = std::nullopt;
  /// The target as a body with cells, its nodes where the target is (the cell-integrated
  /// distance, docs/formulation.md §2.8): an arc's sampling grid as hexahedra whose nodes T
  /// maps (the samples are their centres), a solved_on target's source mesh with the file's
  /// nodes. Empty for a cloud that is only points.
  std::optional<fe::Mesh> cells = std::nullopt;
  /// "quadrature": "collocation" | "cells" (TrackingRunOptions::Distance::quadrature); unset
  /// when the block has none.
  std::optional<Quadrature> quadrature = std::nullopt;
};

/// The objective settings a target asks for: surface → particles boundary with deformed
/// (current) areas; camera → Sides::visible from it (before target_form, which keeps it).
void apply_target_settings(const SceneTarget& target, ShapeObjectiveOptions* options);

/// The start pose of a camera-frame target (docs/formulation.md §8.10): its "pose", else
/// scan::align of the cloud against the moving cloud of `options` at rest (rigid or similarity
/// as "align"; the distance scan_to_body unless the target's is symmetric; no cap; `threads`).
/// Throws InvalidArgument for a body-frame target.
scan::Pose start_pose(const SceneTarget& target, const fe::Assembler& assembler,
                      const ShapeObjectiveOptions& options, int threads = 0);

class ShapeObjective;

/// The DistanceForm of `distance` for `objective`: a fixed cap as given, or the quantile rule
/// applied to the target's field d̃_X(y_j) of the body at rest (u = 0, the start of a run whose
/// start control is 0, the default; docs/guide.md). Throws InvalidArgument as
/// cap_from_quantile.
DistanceForm target_form(const TargetDistance& distance, const ShapeObjective& objective);

/// The arc map of a plate scene (3D box, clamped at X1 = lower): length and thickness from the
/// box, total angle `angle`. Throws InvalidArgument for a 2D scene or an invalid map.
ArcMap arc_map(const Scene& scene, double angle);

/// The scene's own target for the body `mesh` (the scene's mesh). Throws InvalidArgument
/// naming the key for a missing or malformed "target", FileError for its files, and
/// ResourceError if an arc grid's estimated memory exceeds `memory_limit` bytes.
SceneTarget scene_target(const Scene& scene, const fe::Mesh& mesh,
                         double memory_limit = fe::kDefaultMemoryLimit);

/// A target from a cloud file (no known map). Throws FileError, or InvalidArgument if the
/// cloud's dimension differs from `dim` (0: any).
SceneTarget file_target(const std::string& path, int dim = 0);

}  // namespace softhd

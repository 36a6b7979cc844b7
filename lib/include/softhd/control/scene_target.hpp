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
///
/// Either kind also takes "surface": true (the target is a surface scan: the moving cloud is
/// the body's boundary with its current facet areas) and "camera": [x, y, z] (the camera in
/// the body's frame: the distance is the visible one, docs/formulation.md §8.7); 3D only.

#include <Eigen/Core>
#include <optional>
#include <string>

#include "softhd/control/shape_objective.hpp"
#include "softhd/control/targets.hpp"
#include "softhd/fe/mesh.hpp"
#include "softhd/fe/scene.hpp"
#include "softhd/point_cloud.hpp"

namespace softhd {

/// A target cloud and, if T is known, the nodal displacements u_T = T(X) − X of the body.
struct SceneTarget {
  PointCloud cloud;                                 ///< Ω_d
  std::optional<Eigen::VectorXd> map_displacement;  ///< u_T at `mesh`'s nodes, if T is known
  std::string description;                          ///< one line for people
  bool surface = false;                             ///< "surface": the moving cloud is the boundary
  std::optional<Eigen::Vector3d> camera = std::nullopt;  ///< "camera": visible from there
};

/// The objective settings a target asks for: surface → particles boundary with deformed
/// (current) areas; camera → Sides::visible from it.
void apply_target_settings(const SceneTarget& target, ShapeObjectiveOptions* options);

/// The arc map of a plate scene (3D box, clamped at X1 = lower): length and thickness from the
/// box, total angle `angle`. Throws InvalidArgument for a 2D scene or an invalid map.
ArcMap arc_map(const fe::Scene& scene, double angle);

/// The scene's own target for the body `mesh` (the scene's mesh). Throws InvalidArgument
/// naming the key for a missing or malformed "target", FileError for its files, and
/// ResourceError if an arc grid's estimated memory exceeds `memory_limit` bytes.
SceneTarget scene_target(const fe::Scene& scene, const fe::Mesh& mesh,
                         double memory_limit = fe::kDefaultMemoryLimit);

/// A target from a cloud file (no known map). Throws FileError, or InvalidArgument if the
/// cloud's dimension differs from `dim` (0: any).
SceneTarget file_target(const std::string& path, int dim = 0);

}  // namespace softhd

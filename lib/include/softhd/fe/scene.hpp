#pragma once
/// \file scene.hpp
/// Scene files (JSON, docs/formulation.md §5.1/§6.2): the body (structured box mesh), material,
/// fibers, clamp, control space and bounds. The "target" object belongs to the optimiser and is
/// kept as raw JSON text. Invalid files throw FileError naming the key and what was
/// expected.
///
///     { "name": "bending",
///       "mesh": { "type": "box", "lower": [0,0,0], "upper": [10,2,0.1],
///                 "cells": [50,5,2], "order": 2 },
///       "material": { "model": "mooney_rivlin", "a": 1e5, "b": 2e4, "c": 3e5 },
///       "fibers": [1,0,0],
///       "clamp": ["x0"],
///       "constraints": [ { "face": "z0", "components": [2] } ],      (optional)
///       "control": { "space": "vertex", "lower": -1e5, "upper": 0, "initial": 0 },
///       "target": { ... } }                                           (optional)
///
/// Material models: "mooney_rivlin" (a, b, c) and "transversely_isotropic" (a, b, c, d,
/// direction f as an array).
///
/// A body from Gmsh (docs/guide.md, "A body from Gmsh"):
///
///     "mesh": { "type": "gmsh", "file": "finger.msh", "order": 2, "scale": 1 },
///     "materials": { "body": {...}, "layer": {...} },     (or one "material")
///     "fibers": [1, 0, 0] | { "data": "fibres" } | { "file": "f.txt", "per": "element" },
///     "clamp": ["base"],
///     "control": { "space": "vertex", "region": "muscle", "lower": -1e5, "upper": 0 }

#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

#include "softhd/fe/assembly.hpp"
#include "softhd/fe/control.hpp"
#include "softhd/fe/gmsh_mesh.hpp"
#include "softhd/fe/materials.hpp"

namespace softhd::fe {

/// A parsed scene file (docs/guide.md lists every key).
struct Scene {
  std::string name;    ///< "name", or the file name
  std::string source;  ///< file name (for messages)
  /// The body's mesh when it comes from a file (mesh.type "gmsh"); null for a box, whose
  /// mesh make_mesh() generates from lower, upper, cells and order.
  std::shared_ptr<const Mesh> file_mesh;
  std::string mesh_file;  ///< mesh.file as resolved against the scene's folder ("" for a box)
  GmshMeshOptions gmsh_options;  ///< mesh.order and mesh.scale of a file mesh
  ///@{
  /// The body's bounding box: a box's mesh.lower and mesh.upper (2 or 3 entries), or the
  /// bounds of a file mesh's nodes.
  Eigen::VectorXd lower, upper;
  ///@}
  Eigen::VectorXi cells;      ///< mesh.cells: elements per axis (a box; empty for a file mesh)
  int order = 2;              ///< mesh.order: 1 or 2
  int quadrature_degree = 0;  ///< mesh.quadrature_degree (0: the cell's default)
  std::shared_ptr<const Material> material;  ///< "material", or the first of "materials"
  std::string material_model;                ///< its model
  /// One material per mesh region (mesh.region_names order): "materials", or `material`.
  std::vector<std::shared_ptr<const Material>> materials;
  Eigen::Vector3d fibers = Eigen::Vector3d::UnitX();  ///< "fibers" as a vector, normalised
  FiberField fiber_field;  ///< "fibers": the vector, or a field per element or node
  std::vector<DirichletConstraint> constraints;     ///< the clamp, then the extra constraints
  ControlKind control_kind = ControlKind::kVertex;  ///< control.space
  /// control.region: the regions (ids into the mesh's region_names) the control acts on;
  /// empty: the whole body.
  std::vector<int> control_regions;
  ///@{
  /// control.lower, control.upper and control.initial (default 0).
  double control_lower = 0.0, control_upper = 0.0, control_initial = 0.0;
  ///@}
  std::string target_json;  ///< raw "target" object, empty if absent

  /// The body's dimension (2 or 3).
  int dim() const { return static_cast<int>(lower.size()); }
  /// True for a structured box (grid sequencing and arc targets need one).
  bool is_box() const { return file_mesh == nullptr; }
  /// The body's mesh: the structured box mesh, or a copy of the file's.
  Mesh make_mesh() const;
  /// The assembler of the body: mesh, material, fibers and constraints.
  Assembler make_assembler() const;
  /// The control space (control.space, control.region) on `assembler`'s mesh and quadrature.
  ControlSpace make_control_space(const Assembler& assembler) const {
    return ControlSpace(assembler.mesh(), assembler.geometry(), control_kind, control_regions);
  }
  /// residual_floor() (fe/newton.hpp) of this body: its stiffest material and its volume.
  /// The Newton tolerance the solvers use when none is given.
  double residual_floor() const;
  double volume = 0.0;  ///< |Ω₀|: the box's, or the file mesh's (Σ w_q det J0)
};

/// Parses JSON text; `source` names it in error messages. Throws FileError, and
/// ResourceError (before building anything) if the mesh's estimated memory exceeds
/// `memory_limit` bytes (see check_mesh_size).
Scene parse_scene(const std::string& json_text, const std::string& source,
                  double memory_limit = kDefaultMemoryLimit);
/// Reads and parses a scene file. Throws FileError or ResourceError.
Scene load_scene(const std::string& path, double memory_limit = kDefaultMemoryLimit);

}  // namespace softhd::fe

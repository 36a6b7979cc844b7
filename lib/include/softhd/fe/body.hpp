#pragma once
/// \file body.hpp
/// The physical body of a state problem: its mesh (a structured box, or a mesh read from a
/// file), quadrature, materials per region, fibres, constraints and control space with its
/// bounds. A Body is built once, from a scene file (softhd::load_scene,
/// softhd/control/scene.hpp, which checks every key) or in code: box_body() below for a box,
/// or the fields set one by one. Everything in fe/ that solves on a body takes a Body; fe/
/// reads no scene files.

#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

#include "softhd/fe/assembly.hpp"
#include "softhd/fe/control.hpp"
#include "softhd/fe/gmsh_mesh.hpp"
#include "softhd/fe/materials.hpp"

namespace softhd::fe {

/// A body: mesh, materials, fibres, constraints and control (docs/guide.md lists the scene
/// file keys each field comes from).
struct Body {
  /// What the body is called in error messages (a scene's file name); nothing else.
  std::string source;
  /// The body's mesh when it comes from a file (mesh.type "gmsh"); null for a box, whose
  /// mesh make_mesh() generates from lower, upper, cells and order.
  std::shared_ptr<const Mesh> file_mesh;
  std::string mesh_file;         ///< the file of file_mesh ("" for a box)
  GmshMeshOptions gmsh_options;  ///< mesh.order and mesh.scale of a file mesh
  ///@{
  /// The body's bounding box: a box's mesh.lower and mesh.upper (2 or 3 entries), or the
  /// bounds of a file mesh's nodes.
  Eigen::VectorXd lower, upper;
  ///@}
  Eigen::VectorXi cells;      ///< mesh.cells: elements per axis (a box; empty for a file mesh)
  int order = 2;              ///< mesh.order: 1 or 2
  int quadrature_degree = 0;  ///< mesh.quadrature_degree (0: the cell's default)
  /// One material per mesh region (mesh.region_names order; a box has the one region "body").
  std::vector<std::shared_ptr<const Material>> materials;
  FiberField fiber_field;  ///< the fibre direction, or a field per element or node
  std::vector<DirichletConstraint> constraints;     ///< the clamp, then the extra constraints
  ControlKind control_kind = ControlKind::kVertex;  ///< control.space
  /// control.region: the regions (ids into the mesh's region_names) the control acts on;
  /// empty: the whole body.
  std::vector<int> control_regions;
  ///@{
  /// control.lower, control.upper and control.initial (default 0).
  double control_lower = 0.0, control_upper = 0.0, control_initial = 0.0;
  ///@}
  double volume = 0.0;  ///< |Ω₀|: the box's, or the file mesh's (Σ w_q det J0)

  /// The body's dimension (2 or 3).
  int dim() const { return static_cast<int>(lower.size()); }
  /// True for a structured box (halving levels and arc targets need one).
  bool is_box() const { return file_mesh == nullptr; }
  /// The body's mesh: the structured box mesh, or a copy of the file's.
  Mesh make_mesh() const;
  /// The assembler of the body: mesh, materials, fibres and constraints.
  Assembler make_assembler() const;
  /// The control space (control_kind, control_regions) on `assembler`'s mesh and quadrature.
  ControlSpace make_control_space(const Assembler& assembler) const {
    return ControlSpace(assembler.mesh(), assembler.geometry(), control_kind, control_regions);
  }
  /// residual_floor() (fe/newton.hpp) of this body: its stiffest material and its volume.
  /// The Newton tolerance the solvers use when none is given.
  double residual_floor() const;
};

/// A box body made in code, as a scene file's box mesh gives it: [lower, upper] (2 or 3
/// entries) with `cells` elements per axis of `order` (1 or 2), `material` for the whole
/// body, fibres along x, clamped on the boundary sets `clamp` (box faces "x0", "x1", "y0",
/// ...), a vertex control over the whole body with bounds [control_lower, control_upper]
/// starting at 0. Other fields (constraints, control, quadrature, fibres) may be changed
/// after. Throws InvalidArgument on an empty or inverted box, cells < 1, an order other than
/// 1 or 2, a null material or a clamp that names no face.
Body box_body(const Eigen::VectorXd& lower, const Eigen::VectorXd& upper,
              const Eigen::VectorXi& cells, int order, std::shared_ptr<const Material> material,
              const std::vector<std::string>& clamp, double control_lower = 0.0,
              double control_upper = 0.0);

}  // namespace softhd::fe

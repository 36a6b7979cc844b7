#pragma once
/// \file forward.hpp
/// One forward (state) solve of a scene for a given control, as `softhd forward` and the Python
/// `Scene.forward` make it: the control checked against the scene's bounds, optional grid
/// sequencing (a solve on the mesh with half the cells first, interpolated onto the finer
/// nodes), Newton, and the energy, volume and smallest J of the equilibrium.

#include <Eigen/Core>
#include <functional>
#include <string>

#include "softhd/fe/assembly.hpp"
#include "softhd/fe/control.hpp"
#include "softhd/fe/newton.hpp"
#include "softhd/fe/scene.hpp"

namespace softhd::fe {

/// Settings of solve_forward(); defaults per field (those of `softhd forward`).
struct ForwardOptions {
  /// Newton settings; the default adds the step test |du|_inf ≤ 1e-10 |u|_inf.
  NewtonOptions newton = [] {
    NewtonOptions o;
    o.displacement_tolerance = 1e-10;
    return o;
  }();
  /// Grid sequencing: solve first on the mesh with half the cells, `coarse_levels` times
  /// (coarsest first; cell counts must stay even), starting each finer Newton solve from
  /// the coarser state interpolated onto its nodes. 0: start from rest. At most 8.
  int coarse_levels = 0;
  /// Called with the BriefReport of each coarse level's solve (optional).
  std::function<void(const std::string&)> on_coarse_level;

  /// Throws InvalidArgument naming the first invalid field.
  void validate() const;
};

/// The control values on one mesh level: the scene (with that level's cells) and its
/// control space. solve_forward asks for the finest level, then each coarser one.
using LevelControl = std::function<Eigen::VectorXd(const Scene&, const ControlSpace&)>;

/// The equilibrium and what is reported about it.
struct ForwardResult {
  State state;            ///< the equilibrium (or the last converged load step)
  NewtonSummary summary;  ///< the finest level's solve
  double energy = 0.0;    ///< Π(u; m) = ∫ W dX
  double volume = 0.0;    ///< deformed volume ∫ J dX
  double min_J = 0.0;     ///< smallest J over the quadrature points
};

/// The scene with half the cells along every axis. Throws InvalidArgument naming the axis
/// with an odd cell count.
Scene coarsened(const Scene& scene);

/// Throws InvalidArgument naming the first control value outside the scene's bounds (with
/// its position), or if m does not have control.size() entries.
void check_control_bounds(const Scene& scene, const ControlSpace& control, const Mesh& mesh,
                          const Eigen::VectorXd& m);

/// Solves the state of `assembler` (the scene's body) for the control `control_of` gives on
/// the finest level (checked against the bounds). Throws InvalidArgument for bad input, Error
/// if a coarse level does not converge; a finest solve that fails is reported in
/// summary (the state is then the last converged load step).
ForwardResult solve_forward(const Scene& scene, const Assembler& assembler,
                            const ControlSpace& control, const LevelControl& control_of,
                            const ForwardOptions& options = {});

}  // namespace softhd::fe

#pragma once
/// \file forward.hpp
/// One forward (state) solve of a body for a given control, as `softhd forward` and the Python
/// `Scene.forward` make it: the control checked against the body's bounds, grid sequencing
/// (fe/grid_sequencing.hpp), Newton, and the energy, volume and smallest J of the equilibrium.

#include <Eigen/Core>

#include "softhd/fe/assembly.hpp"
#include "softhd/fe/body.hpp"
#include "softhd/fe/control.hpp"
#include "softhd/fe/grid_sequencing.hpp"
#include "softhd/fe/newton.hpp"

namespace softhd::fe {

/// Settings of solve_forward(); defaults per field (those of `softhd forward`).
struct ForwardOptions {
  /// Newton settings; the default adds the step test |du|_inf ≤ 1e-10 |u|_inf.
  NewtonOptions newton = [] {
    NewtonOptions o;
    o.displacement_tolerance = 1e-10;
    return o;
  }();
  GridSequencingOptions grid;  ///< coarse levels solved first (default: automatic)

  /// Throws InvalidArgument naming the first invalid field.
  void validate() const;
};

/// The equilibrium and what is reported about it.
struct ForwardResult {
  State state;                 ///< the equilibrium (or the last converged load step)
  NewtonSummary summary;       ///< the fine solve
  GridSequencingReport grid;   ///< the coarse levels' solves
  double energy = 0.0;         ///< Π(u; m) = ∫ W dX
  double volume = 0.0;         ///< deformed volume ∫ J dX
  double min_J = 0.0;          ///< smallest J over the quadrature points
  double seconds_solve = 0.0;  ///< Newton time of the coarse levels and the fine solve
};

/// Throws InvalidArgument naming the first control value outside the body's bounds (with
/// its position), or if m does not have control.size() entries.
void check_control_bounds(const Body& body, const ControlSpace& control, const Mesh& mesh,
                          const Eigen::VectorXd& m);
/// The same for the body's control space (control.space, control.region) on `mesh`.
void check_control_bounds(const Body& body, const Mesh& mesh, const Eigen::VectorXd& m);

/// Solves the state of `assembler` (`body`'s) for the control m on `control`
/// (checked against the bounds), started by grid sequencing. Throws InvalidArgument for bad
/// input; a fine solve that fails is reported in summary (the state is then the last
/// converged load step).
ForwardResult solve_forward(const Body& body, const Assembler& assembler,
                            const ControlSpace& control, const Eigen::VectorXd& m,
                            const ForwardOptions& options = {});

}  // namespace softhd::fe

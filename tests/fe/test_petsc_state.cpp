// The PETSc state backend (fe/petsc_state.hpp) against the serial CHOLMOD Newton, run under
// mpiexec with any number of ranks (CTest: 2), on boxes and on a Gmsh body. Built only with
// SOFTHD_WITH_MPI.
//
// Expected values come from the serial solver, which tests/fe/test_newton.cpp and
// test_plate.cpp check against analytic limits: both solve R(u; m) = 0 to |R| <= 1e-9 R_ref
// with the step test |du|_inf <= 1e-10 |u|_inf, so their displacements agree to about the
// step tolerance times the condition of the last Newton step; 1e-9 of max|u| is the issue's
// requirement.

#include <gtest/gtest.h>

#include <cstdlib>
#include <initializer_list>
#include <string>

#include "softhd/control/scene.hpp"
#include "softhd/fe/adjoint.hpp"
#include "softhd/fe/forward.hpp"
#include "softhd/fe/petsc_state.hpp"
#include "softhd/fe/state_solver.hpp"

namespace {

using namespace softhd::fe;
using softhd::load_scene;
using softhd::parse_scene;
using softhd::Scene;

Scene scene(const std::string& name) {
  return load_scene(std::string(SOFTHD_SOURCE_DIR) + "/data/scenes/" + name + ".json");
}

// A control linear through the thickness, m = slope X3 at the control positions: bends the
// plate (bending), bends and twists the beam (torsion, the target's m* = -1e6 X3 / 2).
Eigen::VectorXd through_thickness(const Scene& s, double slope) {
  const Assembler a = s.body.make_assembler();
  const ControlSpace c(a.mesh(), a.geometry(), s.body.control_kind);
  return slope * c.positions(a.mesh()).col(2);
}

double relative_difference(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  return (a - b).lpNorm<Eigen::Infinity>() / b.lpNorm<Eigen::Infinity>();
}

// The scene's forward solve by the serial CHOLMOD Newton (solve_forward, as `softhd
// forward`), then by each PETSc backend from the same grid-sequenced start.
void expect_forward_equal(const std::string& name, double slope,
                          std::initializer_list<StateBackend> backends) {
  const Scene s = scene(name);
  const Eigen::VectorXd m = through_thickness(s, slope);
  const Assembler assembler = s.body.make_assembler();
  const ControlSpace control(assembler.mesh(), assembler.geometry(), s.body.control_kind);
  const ForwardResult serial = solve_forward(s.body, assembler, control, m);
  ASSERT_TRUE(serial.summary.converged()) << serial.summary.BriefReport();
  for (StateBackend backend : backends) {
    PetscStateOptions options;
    options.newton = ForwardOptions().newton;
    options.newton.verbose = std::getenv("SOFTHD_TEST_VERBOSE") != nullptr;
    options.backend = backend;
    PetscStateSolver petsc(s.body, options);
    petsc.grid_sequenced_start(s.body, m, GridSequencingOptions());
    const NewtonSummary summary = petsc.solve(m);
    ASSERT_TRUE(summary.converged()) << summary.FullReport();
    const Eigen::VectorXd u = petsc.displacement();
    const double diff = relative_difference(u, serial.state.u);
    std::printf(
        "[rank %d/%d] %s %s: max|u| %.6e, max|du|/max|u| %.3e, %d Newton its, %d solves, "
        "%d CG its\n",
        petsc.layout().rank, petsc.layout().size, name.c_str(), to_string(backend).c_str(),
        serial.state.u.lpNorm<Eigen::Infinity>(), diff, summary.newton_iterations,
        summary.factorizations, summary.krylov_iterations);
    EXPECT_LE(diff, 1e-9) << to_string(backend);
    EXPECT_NEAR(petsc.energy(), serial.energy, 1e-9 * std::abs(serial.energy));
    EXPECT_NEAR(petsc.deformed_volume(), serial.volume, 1e-9 * serial.volume);
  }
}

TEST(PetscState, BendingForwardMumpsEqualsCholmod) {
  expect_forward_equal("bending", -2e4, {StateBackend::kPetscMumps});
}

// CG + GAMG on the thin plate needs about 100 CG iterations per decade of residual (the
// elements' aspect ratio, 0.2 x 0.4 x 0.05, defeats the aggregation): minutes on 2 cores,
// above the suite's budget. Run it with --gtest_also_run_disabled_tests.
TEST(PetscState, DISABLED_BendingForwardGamgEqualsCholmod) {
  expect_forward_equal("bending", -2e4, {StateBackend::kPetscGamg});
}

TEST(PetscState, TorsionForwardEqualsCholmod) {
  expect_forward_equal("torsion", -1e5, {StateBackend::kPetscMumps, StateBackend::kPetscGamg});
}

// A body from Gmsh (data/scenes/finger.json: P2 tetrahedra of an unstructured mesh, two
// materials, clamped on a physical surface), cut by the coordinate bisection of its
// elements: m = -0.5 X3 (a third of the target's control, for the suite's time).
TEST(PetscState, FingerForwardEqualsCholmod) {
  expect_forward_equal("finger", -0.5, {StateBackend::kPetscMumps, StateBackend::kPetscGamg});
}

}  // namespace

#pragma once
// softhd._core.Scene: a scene file with its body's assembler and control space, built once.

#include "common.hpp"
#include "softhd/control/scene.hpp"
#include "softhd/fe/assembly.hpp"
#include "softhd/fe/control.hpp"

namespace softhd::python {

/// A loaded scene, its assembler and its control space (shared by forward and optimise).
struct PyScene {
  explicit PyScene(softhd::Scene s)
      : scene(std::move(s)),
        assembler(scene.body.make_assembler()),
        control(scene.body.make_control_space(assembler)) {}
  PyScene(const PyScene&) = delete;
  PyScene& operator=(const PyScene&) = delete;

  softhd::Scene scene;
  fe::Assembler assembler;
  fe::ControlSpace control;
};

/// The (num_nodes, dim) array of a node-major vector (num_nodes · dim entries).
py::array_t<double> node_rows(const Eigen::VectorXd& u, int dim);

}  // namespace softhd::python

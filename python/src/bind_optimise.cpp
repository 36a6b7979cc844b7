// softhd._core.optimise: a shape-tracking run (track_shape) on a loaded scene, with a Python
// callback after every accepted iteration that can end the run.

#include <pybind11/eigen.h>
#include <pybind11/stl.h>

#include "scene.hpp"
#include "softhd/control/scene_target.hpp"
#include "softhd/control/shape_objective.hpp"
#include "softhd/control/shape_tracking.hpp"
#include "softhd/error.hpp"
#include "softhd/fe/grid_sequencing.hpp"

namespace softhd::python {

namespace {

/// One accepted iteration as the callback sees it: the record and the best control so far.
struct PyIteration {
  TrackingIteration record;
  Eigen::VectorXd control;
};

/// What optimise returns: the summary, with displacements as (num_nodes, dim) rows.
struct PyOptimise {
  ShapeTrackingSummary summary;
  int dim = 3;
  std::string target;  // the target's description
};

struct OptimiseArgs {
  int max_iter = 200;
  double max_seconds = 0.0, rel_tol = 1e-6, move_limit = 0.1;
  std::string algorithm = "mma", particles = "nodes", volumes = "reference";
  double tikhonov_mass = 0.0, tikhonov_grad = 0.0;
  std::string coarse_level = "auto";  // two-level starts, as softhd optimise --coarse-level
};

SceneTarget make_target(const PyScene& s, const std::optional<Array>& points,
                        const std::optional<Array>& volumes,
                        const std::optional<std::string>& file) {
  if (file) return file_target(*file, s.scene.dim());
  if (!points) return scene_target(s.scene, s.assembler.mesh());
  check_cloud(*points, volumes, "target");
  PointCloud cloud = make_cloud(*points, volumes);
  if (cloud.dim() != s.scene.dim())
    throw InvalidArgument("the target cloud is " + std::to_string(cloud.dim()) +
                          "D but the scene's body is " + std::to_string(s.scene.dim()) + "D");
  return {std::move(cloud), std::nullopt, "arrays from Python"};
}

PyOptimise optimise(const PyScene& s, const std::optional<Array>& points,
                    const std::optional<Array>& volumes, const std::optional<std::string>& file,
                    const OptimiseArgs& a, const HausdorffOptions& hausdorff,
                    const py::object& callback, int threads) {
  if (a.max_iter < 1) throw InvalidArgument("max_iter must be >= 1");
  if (a.coarse_level != "auto" && a.coarse_level != "off")
    throw InvalidArgument("coarse_level must be \"auto\" or \"off\", got \"" + a.coarse_level +
                          "\"");
  ShapeTrackingOptions to;
  BoundedOptimizerOptions& opt = to.optimizer;
  opt.max_iterations = a.max_iter;
  opt.max_evaluations = 5 * a.max_iter + 20;  // as softhd optimise
  opt.max_seconds = a.max_seconds;
  opt.relative_change = a.rel_tol;
  opt.algorithm = algorithm_from_string(a.algorithm);
  opt.move_limit = a.move_limit;
  to.validate();
  ShapeObjectiveOptions so;
  so.hausdorff = hausdorff;
  so.particles = particles_from_string(a.particles);
  so.volumes = particle_volumes_from_string(a.volumes);
  so.tikhonov_mass = a.tikhonov_mass;
  so.tikhonov_gradient = a.tikhonov_grad;
  so.validate();
  ThreadScope scope(threads);
  ShapeTrackingCallbacks cb;
  if (!callback.is_none()) {
    // Returning False (the object itself, not any false value) ends the run; an exception
    // raised by the callback ends it too and propagates out of optimise.
    cb.on_iteration = [&](const TrackingIteration& it, const Eigen::VectorXd& m) {
      py::gil_scoped_acquire acquire;
      const py::object r = callback(PyIteration{it, m});
      if (r.ptr() == Py_False) throw StopRequest{};
    };
  }
  py::gil_scoped_release release;
  const SceneTarget target = make_target(s, points, volumes, file);
  ShapeObjective objective(s.assembler, s.control, HausdorffTarget(target.cloud, so.hausdorff), so);
  std::optional<fe::Assembler> coarse;  // as softhd optimise: a coarser mesh if there is one
  if (a.coarse_level == "auto" && fe::grid_levels(s.scene, fe::GridSequencingOptions{}) > 0) {
    coarse.emplace(fe::coarsened(s.scene).make_assembler());
    objective.use_coarse_level(*coarse);
  }
  const Eigen::VectorXd m0 = s.control.constant(s.scene.control_initial);
  const Eigen::VectorXd lower = s.control.constant(s.scene.control_lower);
  const Eigen::VectorXd upper = s.control.constant(s.scene.control_upper);
  PyOptimise out;
  out.summary = track_shape(objective, lower, upper, m0, target.map_displacement, to, cb);
  out.dim = s.scene.dim();
  out.target = target.description;
  return out;
}

py::object optional(const std::optional<double>& v) {
  return v ? py::object(py::float_(*v)) : py::object(py::none());
}

void bind_records(py::module_& m) {
  py::class_<PyIteration>(m, "Iteration", "One accepted iteration of optimise.")
      .def_property_readonly("iteration", [](const PyIteration& i) { return i.record.iteration; })
      .def_property_readonly("evaluation", [](const PyIteration& i) { return i.record.evaluation; })
      .def_property_readonly("J", [](const PyIteration& i) { return i.record.J; })
      .def_property_readonly("rho", [](const PyIteration& i) { return i.record.rho; })
      .def_property_readonly("A", [](const PyIteration& i) { return i.record.A; })
      .def_property_readonly("B", [](const PyIteration& i) { return i.record.B; })
      .def_property_readonly("rho_over_floor",
                             [](const PyIteration& i) { return i.record.rho_over_floor; })
      .def_property_readonly("projected_gradient_norm",
                             [](const PyIteration& i) { return i.record.projected_gradient_norm; })
      .def_property_readonly("newton_iterations",
                             [](const PyIteration& i) { return i.record.newton_iterations; })
      .def_property_readonly("seconds", [](const PyIteration& i) { return i.record.seconds; })
      .def_property_readonly(
          "control", [](const PyIteration& i) { return i.control; },
          "the best control so far (a copy)")
      .def("__repr__", [](const PyIteration& i) {
        return "Iteration(" + std::to_string(i.record.iteration) +
               ", J=" + std::to_string(i.record.J) + ", rho=" + std::to_string(i.record.rho) + ")";
      });
}

}  // namespace

void bind_optimise(py::module_& m) {
  bind_records(m);
  py::class_<PyOptimise>(m, "OptimiseResult", "The result of optimise.")
      .def_property_readonly("rho_start", [](const PyOptimise& r) { return r.summary.rho_start; })
      .def_property_readonly("rho_final", [](const PyOptimise& r) { return r.summary.rho_final; })
      .def_property_readonly("J_final", [](const PyOptimise& r) { return r.summary.J_final; })
      .def_property_readonly("floor_self",
                             [](const PyOptimise& r) { return optional(r.summary.floor_self); })
      .def_property_readonly("floor_matched",
                             [](const PyOptimise& r) { return optional(r.summary.floor_matched); })
      .def_property_readonly("iterations", [](const PyOptimise& r) { return r.summary.iterations; })
      .def_property_readonly("evaluations",
                             [](const PyOptimise& r) { return r.summary.evaluations; })
      .def_property_readonly("failed_evaluations",
                             [](const PyOptimise& r) { return r.summary.failed_evaluations; })
      .def_property_readonly("termination",
                             [](const PyOptimise& r) { return r.summary.termination; })
      .def_property_readonly(
          "status", [](const PyOptimise& r) { return to_string(r.summary.status); },
          "why it stopped: iteration_limit, relative_change, stopped, ... (converged or not)")
      .def_property_readonly("converged", [](const PyOptimise& r) { return r.summary.converged(); })
      .def_property_readonly(
          "shape_error_max",
          [](const PyOptimise& r) { return optional(r.summary.shape_error_max); })
      .def_property_readonly(
          "shape_error_rms",
          [](const PyOptimise& r) { return optional(r.summary.shape_error_rms); })
      .def_property_readonly("seconds", [](const PyOptimise& r) { return r.summary.seconds; })
      .def_property_readonly("control", [](const PyOptimise& r) { return r.summary.control; })
      .def_property_readonly(
          "displacements",
          [](const PyOptimise& r) { return node_rows(r.summary.displacement, r.dim); })
      .def_property_readonly("history",
                             [](const PyOptimise& r) {
                               std::vector<PyIteration> h;
                               for (const TrackingIteration& it : r.summary.history)
                                 h.push_back({it, Eigen::VectorXd()});
                               return h;
                             })
      .def_property_readonly("target", [](const PyOptimise& r) { return r.target; })
      .def("__repr__",
           [](const PyOptimise& r) { return "OptimiseResult(" + r.summary.BriefReport() + ")"; });

  m.def(
      "optimise",
      [](const PyScene& s, const std::optional<Array>& points, const std::optional<Array>& volumes,
         const std::optional<std::string>& file, int max_iter, double max_seconds, double rel_tol,
         const std::string& algorithm, double move_limit, const std::string& particles,
         const std::string& volumes_kind, double alpha, double beta, double gamma, double eps,
         const std::string& method, double tol, double tikhonov_mass, double tikhonov_grad,
         const std::string& coarse_level, const py::object& callback, int threads) {
        OptimiseArgs a{max_iter,  max_seconds,  rel_tol,       move_limit,    algorithm,
                       particles, volumes_kind, tikhonov_mass, tikhonov_grad, coarse_level};
        HausdorffOptions h;
        h.params = {alpha, beta, gamma, eps};
        h.method = method_from_string(method);
        h.tolerance = tol;
        h.threads = threads;
        return optimise(s, points, volumes, file, a, h, callback, threads);
      },
      py::arg("scene"), py::arg("points").noconvert(), py::arg("volumes").noconvert(),
      py::arg("file"), py::kw_only(), py::arg("max_iter"), py::arg("max_seconds"),
      py::arg("rel_tol"), py::arg("algorithm"), py::arg("move_limit"), py::arg("particles"),
      py::arg("volumes_kind"), py::arg("alpha"), py::arg("beta"), py::arg("gamma"), py::arg("eps"),
      py::arg("method"), py::arg("tol"), py::arg("tikhonov_mass"), py::arg("tikhonov_grad"),
      py::arg("coarse_level"), py::arg("callback"), py::arg("threads"));
}

}  // namespace softhd::python

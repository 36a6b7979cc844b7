// softhd._core.optimise: a tracking run (TrackingRun, the one `softhd optimise` makes) on a loaded
// scene, with a Python callback after every accepted iteration that can end the run.

#include <pybind11/eigen.h>
#include <pybind11/stl.h>

#include <memory>

#include "scene.hpp"
#include "softhd/control/run_fields.hpp"
#include "softhd/control/scene_target.hpp"
#include "softhd/control/tracking_run.hpp"
#include "softhd/error.hpp"

namespace softhd::python {

namespace {

/// One accepted iteration as the callback sees it: the record and the best control so far.
struct PyIteration {
  TrackingIteration record;
  Eigen::VectorXd control;
};

/// What optimise returns: the summary, with displacements as (num_nodes, dim) rows.
struct PyOptimise {
  TrackingRunSummary summary;
  int dim = 3;
};

/// The target given as arrays, checked against the scene's dimension.
SceneTarget array_target(const PyScene& s, const Array& points,
                         const std::optional<Array>& volumes) {
  check_cloud(points, volumes, "target");
  PointCloud cloud = make_cloud(points, volumes);
  if (cloud.dim() != s.scene.body.dim())
    throw InvalidArgument("the target cloud is " + std::to_string(cloud.dim()) +
                          "D but the scene's body is " + std::to_string(s.scene.body.dim()) + "D");
  return {std::move(cloud), std::nullopt, "arrays from Python", {}};
}

PyOptimise optimise(const PyScene& s, const std::optional<Array>& points,
                    const std::optional<Array>& volumes, const std::optional<std::string>& file,
                    TrackingRunOptions o, const py::object& callback) {
  if (file) o.target.file = *file;
  validate_naming_fields(o, FrontEnd::python);  // the fields by their keywords
  ThreadScope scope(o.threads);                 // the FE assembly's threads too
  TrackingRunCallbacks cb;
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
  SceneTarget target =
      points ? array_target(s, *points, volumes) : tracking_target(s.scene, s.assembler.mesh(), o);
  std::unique_ptr<TrackingRun> run;
  try {
    run = std::make_unique<TrackingRun>(s.scene, s.assembler, s.control, std::move(target), o);
  } catch (const InvalidArgument& e) {
    throw InvalidArgument(name_fields(e.what(), FrontEnd::python));
  }
  PyOptimise out;
  out.summary = run->run(cb);
  out.dim = s.scene.body.dim();
  return out;
}

/// The defaults of optimise's keyword arguments: TrackingRunOptions'.
py::dict optimise_defaults() {
  const TrackingRunOptions d;
  py::dict out;
  out["max_iter"] = d.optimiser.max_iterations;
  out["initial"] = py::none();  // the scene's control.initial
  out["pose_move"] = d.pose.move;
  out["pose_method"] = to_string(d.pose.method);
  out["quadrature"] = py::none();  // the scene target's "quadrature", else collocation
  out["max_seconds"] = d.optimiser.max_seconds;
  out["rel_tol"] = d.optimiser.relative_change;
  out["algorithm"] = to_string(d.optimiser.algorithm);
  out["hessian"] = to_string(d.optimiser.hessian);
  out["move_limit"] = d.optimiser.move_limit;
  out["particles"] = to_string(d.distance.particles);
  out["volumes"] = to_string(d.distance.volumes);
  out["alpha"] = d.distance.params.alpha;
  out["beta"] = d.distance.params.beta;
  out["gamma"] = d.distance.params.gamma;
  out["eps"] = d.distance.params.epsilon;
  out["method"] = to_string(d.distance.method);
  out["tol"] = d.distance.tolerance;
  out["tikhonov_mass"] = d.tikhonov.mass;
  out["tikhonov_grad"] = d.tikhonov.gradient;
  out["coarse_levels"] = to_string(d.state.coarse_levels);
  out["levels"] = d.levels.count;
  out["refined_move_limit"] = d.levels.refined_move_limit;
  out["coarse_iterations"] = d.levels.coarse_iterations;
  out["switch_decrease"] = d.levels.switch_decrease;
  out["coarse_tol"] = d.levels.coarse_tolerance;
  // The form is the target's unless given (TrackingRunOptions::distance).
  out["distance"] = py::none();
  out["cap"] = py::none();
  out["cap_q"] = py::none();
  out["threads"] = d.threads;
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
      .def_property_readonly("factorizations",
                             [](const PyIteration& i) { return i.record.factorizations; })
      .def_property_readonly("seconds_state",
                             [](const PyIteration& i) { return i.record.seconds_state; })
      .def_property_readonly("seconds_distance",
                             [](const PyIteration& i) { return i.record.seconds_distance; })
      .def_property_readonly("seconds_adjoint",
                             [](const PyIteration& i) { return i.record.seconds_adjoint; })
      .def_property_readonly("seconds", [](const PyIteration& i) { return i.record.seconds; })
      .def_property_readonly(
          "level", [](const PyIteration& i) { return i.record.level; },
          "the multilevel level: times the user's mesh was halved for it (0: the user's mesh)")
      .def_property_readonly(
          "control", [](const PyIteration& i) { return i.control; },
          "the best control so far (a copy)")
      .def("__repr__", [](const PyIteration& i) {
        return "Iteration(" + std::to_string(i.record.iteration) +
               ", J=" + std::to_string(i.record.J) + ", rho=" + std::to_string(i.record.rho) + ")";
      });
}

/// softhd.OptimiseResult: the summary of a run as read-only properties.
void bind_optimise_result(py::module_& m) {
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
          "pose",
          [](const PyOptimise& r) -> py::object {
            if (!r.summary.pose) return py::none();
            return py::cast(Eigen::Matrix4d(r.summary.pose->matrix()));
          },
          "a target in the camera's frame: the 4x4 pose (scan -> body) found with the control; "
          "else None")
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
      .def_property_readonly("target", [](const PyOptimise& r) { return r.summary.target; })
      .def("__repr__",
           [](const PyOptimise& r) { return "OptimiseResult(" + r.summary.BriefReport() + ")"; });
}

}  // namespace

void bind_optimise(py::module_& m) {
  bind_records(m);
  bind_optimise_result(m);
  // Every option None keeps TrackingRunOptions' default (softhd optimise's).
  m.def(
      "optimise",
      [](const PyScene& s, const std::optional<Array>& points, const std::optional<Array>& volumes,
         const std::optional<std::string>& file, std::optional<int> max_iter,
         std::optional<double> max_seconds, std::optional<double> rel_tol,
         const std::optional<std::string>& algorithm, const std::optional<std::string>& hessian,
         std::optional<double> move_limit, const std::optional<std::string>& particles,
         const std::optional<std::string>& volumes_kind, std::optional<double> alpha,
         std::optional<double> beta, std::optional<double> gamma, std::optional<double> eps,
         const std::optional<std::string>& method, std::optional<double> tol,
         std::optional<double> tikhonov_mass, std::optional<double> tikhonov_grad,
         const std::optional<std::string>& coarse_levels, std::optional<int> levels,
         std::optional<double> refined_move_limit, std::optional<int> coarse_iterations,
         std::optional<double> switch_decrease, std::optional<double> coarse_tol,
         const std::optional<std::string>& distance, std::optional<double> cap,
         std::optional<double> cap_q, const std::optional<Eigen::VectorXd>& initial,
         std::optional<double> pose_move, const std::optional<std::string>& pose_method,
         const std::optional<std::string>& quadrature, const py::object& callback, int threads) {
        TrackingRunOptions o;
        if (quadrature) o.distance.quadrature = quadrature_from_string(*quadrature);
        if (initial) o.optimiser.initial_control = *initial;
        if (pose_move) o.pose.move = *pose_move;
        if (pose_method) {
          try {
            o.pose.method = pose_method_from_string(*pose_method);
          } catch (const InvalidArgument& e) {  // named by its keyword
            throw InvalidArgument(name_fields(e.what(), FrontEnd::python));
          }
        }
        if (distance || cap || cap_q) {  // the form as a whole (TrackingRunOptions::distance)
          TargetDistance form;
          if (distance) form.sides = sides_from_string(*distance);
          if (cap) form.cap = *cap;
          if (cap_q) form.cap_q = *cap_q;
          o.distance.form = form;
        }
        if (max_iter) o.optimiser.max_iterations = *max_iter;
        if (max_seconds) o.optimiser.max_seconds = *max_seconds;
        if (rel_tol) o.optimiser.relative_change = *rel_tol;
        if (algorithm) o.optimiser.algorithm = algorithm_from_string(*algorithm);
        if (hessian) o.optimiser.hessian = hessian_part_from_string(*hessian, "hessian");
        if (move_limit) o.optimiser.move_limit = *move_limit;
        if (particles) o.distance.particles = particles_from_string(*particles);
        if (volumes_kind) o.distance.volumes = particle_volumes_from_string(*volumes_kind);
        if (alpha) o.distance.params.alpha = *alpha;
        if (beta) o.distance.params.beta = *beta;
        if (gamma) o.distance.params.gamma = *gamma;
        if (eps) o.distance.params.epsilon = *eps;
        if (method) o.distance.method = method_from_string(*method);
        if (tol) o.distance.tolerance = *tol;
        if (tikhonov_mass) o.tikhonov.mass = *tikhonov_mass;
        if (tikhonov_grad) o.tikhonov.gradient = *tikhonov_grad;
        if (coarse_levels) {
          try {
            o.state.coarse_levels = coarse_level_from_string(*coarse_levels);
          } catch (const InvalidArgument& e) {  // named by its keyword
            throw InvalidArgument(name_fields(e.what(), FrontEnd::python));
          }
        }
        if (levels) o.levels.count = *levels;
        if (refined_move_limit) o.levels.refined_move_limit = *refined_move_limit;
        if (coarse_iterations) o.levels.coarse_iterations = *coarse_iterations;
        if (switch_decrease) o.levels.switch_decrease = *switch_decrease;
        if (coarse_tol) o.levels.coarse_tolerance = *coarse_tol;
        o.threads = threads;
        return optimise(s, points, volumes, file, o, callback);
      },
      py::arg("scene"), py::arg("points").noconvert(), py::arg("volumes").noconvert(),
      py::arg("file"), py::kw_only(), py::arg("max_iter"), py::arg("max_seconds"),
      py::arg("rel_tol"), py::arg("algorithm"), py::arg("hessian"), py::arg("move_limit"),
      py::arg("particles"), py::arg("volumes_kind"), py::arg("alpha"), py::arg("beta"),
      py::arg("gamma"), py::arg("eps"), py::arg("method"), py::arg("tol"), py::arg("tikhonov_mass"),
      py::arg("tikhonov_grad"), py::arg("coarse_levels"), py::arg("levels"),
      py::arg("refined_move_limit"), py::arg("coarse_iterations"), py::arg("switch_decrease"),
      py::arg("coarse_tol"), py::arg("distance"), py::arg("cap"), py::arg("cap_q"),
      py::arg("initial"), py::arg("pose_move"), py::arg("pose_method"), py::arg("quadrature"),
      py::arg("callback"), py::arg("threads"));
  m.def(
      "optimise_fields",
      [] {
        py::list rows;
        for (const RunField& f : tracking_run_fields())
          rows.append(py::dict(py::arg("path") = f.path, py::arg("flag") = f.flag,
                               py::arg("keyword") = f.keyword, py::arg("why_not") = f.why_not));
        return rows;
      },
      "The fields of the run's options (TrackingRunOptions) by their nested path, with the flag "
      "of softhd optimise and the keyword of optimise that set each one (\"\": none, why_not "
      "says why).");
  m.def("optimise_defaults", &optimise_defaults,
        "The defaults of optimise's options (softhd optimise's: TrackingRunOptions).");
}

}  // namespace softhd::python

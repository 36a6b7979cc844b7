// softhd._core.Scene and ForwardResult: scene files and fe::solve_forward.

#include <pybind11/eigen.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <sstream>

#include "mesh.hpp"
#include "scene.hpp"
#include "softhd/error.hpp"
#include "softhd/fe/forward.hpp"
#include "softhd/fe/locator.hpp"
#include "softhd/fe/output.hpp"

namespace softhd::python {

namespace {

/// What Scene.forward returns.
struct PyForward {
  py::array_t<double> displacements;  // (num_nodes, dim)
  double energy = 0.0, volume = 0.0, min_J = 0.0;
  py::array_t<double> probes;  // (P, dim) u at the probe points
  bool converged = false;
  std::string status, report;
  int newton_iterations = 0, load_steps = 0, factorizations = 0;
};

std::vector<Eigen::VectorXd> probe_points(const PyScene& s, const Eigen::MatrixXd& probes) {
  const int dim = s.scene.body.dim();
  if (probes.size() > 0 && probes.cols() != dim)
    throw InvalidArgument("probes must be a (P, " + std::to_string(dim) + ") array, got " +
                          std::to_string(probes.cols()) + " columns");
  std::vector<Eigen::VectorXd> points;
  const fe::PointLocator locator(s.assembler.mesh());
  for (Eigen::Index p = 0; p < probes.rows(); ++p) {
    Eigen::VectorXd xi;
    if (locator.locate(probes.row(p).transpose(), &xi) < 0) {
      std::ostringstream os;
      os << "probe (" << probes.row(p) << ") is not a point of the " << dim << "D body";
      throw InvalidArgument(os.str());
    }
    points.push_back(probes.row(p).transpose());
  }
  return points;
}

PyForward forward(const PyScene& s, const py::object& control, const Eigen::MatrixXd& probes,
                  int coarse_levels, int threads) {
  // control: None (the scene's initial value), a number (uniform: a Python int or float, a
  // NumPy scalar or a 0-d array) or one value per control.
  const bool number = py::isinstance<py::float_>(control) || py::isinstance<py::int_>(control) ||
                      py::isinstance(control, py::module_::import("numpy").attr("number")) ||
                      (py::isinstance<py::array>(control) &&
                       py::reinterpret_borrow<py::array>(control).ndim() == 0);
  Eigen::VectorXd m;
  if (control.is_none() || number)
    m = s.control.constant(control.is_none() ? s.scene.body.control_initial
                                             : control.cast<double>());
  else
    m = control.cast<Eigen::VectorXd>();
  const std::vector<Eigen::VectorXd> points = probe_points(s, probes);
  fe::ForwardOptions options;
  options.grid.levels = coarse_levels;
  ThreadScope scope(threads);
  std::optional<fe::ForwardResult> r;
  Eigen::MatrixXd u_probes(points.size(), s.scene.body.dim());
  {
    py::gil_scoped_release release;
    r.emplace(fe::solve_forward(s.scene.body, s.assembler, s.control, m, options));
    for (size_t p = 0; p < points.size(); ++p)
      u_probes.row(static_cast<Eigen::Index>(p)) =
          fe::probe_displacement(s.assembler, r->state.u, points[p]).transpose();
  }
  PyForward out;
  out.displacements = node_rows(r->state.u, s.scene.body.dim());
  out.energy = r->energy;
  out.volume = r->volume;
  out.min_J = r->min_J;
  out.probes = to_numpy(u_probes);
  out.converged = r->summary.converged();
  out.status = fe::to_string(r->summary.status);
  out.report = r->summary.BriefReport();
  out.newton_iterations = r->summary.newton_iterations;
  out.load_steps = r->summary.load_steps;
  out.factorizations = r->summary.factorizations;
  return out;
}

}  // namespace

py::array_t<double> node_rows(const Eigen::VectorXd& u, int dim) {
  return to_numpy(Eigen::Map<const RowMatrix>(u.data(), u.size() / dim, dim));
}

void bind_fe(py::module_& m) {
  py::class_<PyForward>(m, "ForwardResult", "The equilibrium of Scene.forward.")
      .def_readonly("displacements", &PyForward::displacements, "(num_nodes, dim) u at the nodes")
      .def_readonly("energy", &PyForward::energy, "stored energy Pi = int W dX")
      .def_readonly("volume", &PyForward::volume, "deformed volume int J dX")
      .def_readonly("min_J", &PyForward::min_J, "smallest J at the quadrature points")
      .def_readonly("probes", &PyForward::probes, "(P, dim) u at the probe points")
      .def_readonly("converged", &PyForward::converged)
      .def_readonly("status", &PyForward::status)
      .def_readonly("report", &PyForward::report, "Newton's one-line report")
      .def_readonly("newton_iterations", &PyForward::newton_iterations)
      .def_readonly("load_steps", &PyForward::load_steps)
      .def_readonly("factorizations", &PyForward::factorizations)
      .def("__repr__", [](const PyForward& f) {
        return "ForwardResult(" + f.report + ", energy=" + std::to_string(f.energy) + ")";
      });

  py::class_<PyScene>(m, "Scene", "A scene file: body, material, clamp, controls, target.")
      .def_static(
          "load",
          [](const std::filesystem::path& path, double max_memory_gib) {
            if (!(max_memory_gib > 0.0 && max_memory_gib <= 1e6))
              throw InvalidArgument("max_memory_gib must be in (0, 1e6]");
            py::gil_scoped_release release;
            return std::make_unique<PyScene>(
                softhd::load_scene(path.string(), max_memory_gib * (1u << 30)));
          },
          py::arg("path"), py::arg("max_memory_gib") = 8.0,
          "Reads a scene file (JSON, docs/guide.md). Raises FileError for a missing or malformed "
          "file, ResourceError if the mesh's estimated memory exceeds max_memory_gib.")
      .def_property_readonly("name", [](const PyScene& s) { return s.scene.name; })
      .def_property_readonly("dim", [](const PyScene& s) { return s.scene.body.dim(); })
      .def_property_readonly("nodes",
                             [](const PyScene& s) { return to_numpy(s.assembler.mesh().nodes); })
      .def_property_readonly(
          "mesh", [](const PyScene& s) { return mesh_of(s.assembler); },
          "The body's Mesh (a copy): the generated box, or the scene's Gmsh file as read")
      .def_property_readonly("num_controls", [](const PyScene& s) { return s.control.size(); })
      .def_property_readonly(
          "control_positions",
          [](const PyScene& s) { return to_numpy(s.control.positions(s.assembler.mesh())); })
      .def_property_readonly("control_bounds",
                             [](const PyScene& s) {
                               return py::make_tuple(s.scene.body.control_lower,
                                                     s.scene.body.control_upper);
                             })
      .def_property_readonly("control_initial",
                             [](const PyScene& s) { return s.scene.body.control_initial; })
      .def_property_readonly("has_target",
                             [](const PyScene& s) { return !s.scene.target_json.empty(); })
      .def(
          "control_at_nodes",
          [](const PyScene& s, const Eigen::VectorXd& m) {
            if (m.size() != s.control.size())
              throw InvalidArgument("the control has " + std::to_string(m.size()) +
                                    " values but the scene has " +
                                    std::to_string(s.control.size()) + " controls");
            return fe::control_at_nodes(s.assembler.mesh(), s.control, m);
          },
          py::arg("control"),
          "The control interpolated at every node (vertex controls; zeros for element ones).")
      .def("forward", &forward, py::arg("control") = py::none(), py::kw_only(),
           py::arg("probes") = Eigen::MatrixXd(0, 0), py::arg("coarse_levels") = -1,
           py::arg("threads") = 0,
           "The equilibrium for the control m: None (the scene's control.initial), a number "
           "(uniform) or an array of num_controls values within the scene's bounds. probes: "
           "(P, dim) reference points where u is interpolated. coarse_levels: grid sequencing "
           "(a box halved K times; a file mesh of order 2 solved as P1/Q1 on its vertices "
           "first), -1 automatic (as softhd forward), 0 none, K levels. Same solve as `softhd "
           "forward`. A "
           "Newton failure is "
           "reported in the result (converged, status, report), not raised.");
}

}  // namespace softhd::python

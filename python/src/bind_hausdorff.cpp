// softhd._core.Target and DistanceResult: HausdorffTarget and HausdorffResult.

#include <sstream>

#include "common.hpp"
#include "softhd/error.hpp"
#include "softhd/hausdorff.hpp"

namespace softhd::python {

namespace {

HausdorffOptions make_options(double alpha, double beta, double gamma, double eps,
                              const std::string& method, double tol, int threads) {
  HausdorffOptions o;
  o.params.alpha = alpha;
  o.params.beta = beta;
  o.params.gamma = gamma;
  o.params.epsilon = eps;
  o.method = method_from_string(method);
  o.tolerance = tol;
  o.threads = threads;
  return o;  // validated by the HausdorffTarget constructor
}

HausdorffTarget make_target(const Array& Y, const std::optional<Array>& VY, double alpha,
                            double beta, double gamma, double eps, const std::string& method,
                            double tol, int threads) {
  check_cloud(Y, VY, "Y");
  const HausdorffOptions options = make_options(alpha, beta, gamma, eps, method, tol, threads);
  py::gil_scoped_release release;
  return HausdorffTarget(make_cloud(Y, VY), options);
}

/// The distance form of docs/formulation.md §8 from the keyword arguments (validated by the
/// evaluation, which names the field).
DistanceForm make_form(const std::string& distance, double cap, double cap_q,
                       const std::optional<py::array_t<bool, py::array::c_style>>& camera_mask) {
  DistanceForm form;
  form.sides = sides_from_string(distance);
  form.cap.c = cap;
  form.cap.q = cap_q;
  if (camera_mask) {
    if (camera_mask->ndim() != 1)
      throw InvalidArgument("camera_mask must be a 1-D array of N booleans, got " +
                            std::to_string(camera_mask->ndim()) + " dimensions");
    form.camera_mask = Eigen::Map<const Eigen::Array<bool, Eigen::Dynamic, 1>>(
        camera_mask->data(), camera_mask->shape(0));
  }
  return form;
}

HausdorffResult evaluate(const HausdorffTarget& target, const Array& X,
                         const std::optional<Array>& VX, bool fields, bool gradient,
                         bool gradient_volumes, bool gradient_target, const std::string& distance,
                         double cap, double cap_q,
                         const std::optional<py::array_t<bool, py::array::c_style>>& camera_mask,
                         bool hessian) {
  check_cloud(X, VX, "X");
  HausdorffRequest request;
  request.hessian_points = hessian;
  request.form = make_form(distance, cap, cap_q, camera_mask);
  request.fields = fields;
  request.gradient_points = gradient;
  request.gradient_volumes = gradient_volumes;
  request.gradient_target = gradient_target;
  py::gil_scoped_release release;
  return target.evaluate(make_cloud(X, VX), request);
}

/// H·V (part "full") or H_GN·V ("gauss_newton") at the moving cloud of `at`
/// (HausdorffTarget::hessian_product), as a new (N, d) array.
py::array_t<double> hessian_product(const HausdorffTarget& target, const HausdorffResult& at,
                                    const Array& V, const std::string& part) {
  if (V.ndim() != 2)
    throw InvalidArgument("V must be an (N, d) array, got " + std::to_string(V.ndim()) +
                          " dimensions");
  HessianPart which = HessianPart::full;
  if (part == "gauss_newton")
    which = HessianPart::gauss_newton;
  else if (part != "full")
    throw InvalidArgument("part must be 'full' or 'gauss_newton', got '" + part + "'");
  const Eigen::MatrixXd v = Eigen::Map<const RowMatrix>(V.data(), V.shape(0), V.shape(1));
  RowMatrix out;
  {
    py::gil_scoped_release release;
    out = target.hessian_product(at, v, which);
  }
  return to_numpy(out);
}

std::string result_repr(const HausdorffResult& r) {
  std::ostringstream s;
  s.precision(10);
  s << "DistanceResult(rho=" << r.rho << ", A=" << r.A << ", B=" << r.B << ", seconds=" << r.seconds
    << ")";
  return s.str();
}

}  // namespace

void bind_hausdorff(py::module_& m) {
  py::class_<HausdorffResult>(m, "DistanceResult",
                              "The result of one evaluation. Arrays are read-write views of the "
                              "result's own memory (no copy); None when not requested.")
      .def_readonly("rho", &HausdorffResult::rho, "rho_H (method nearest: Hausdorff distance)")
      .def_readonly("A", &HausdorffResult::A, "target-over-moving mean (of capped values)")
      .def_readonly("B", &HausdorffResult::B,
                    "moving-over-target mean (visible points only for distance='visible'; 0 "
                    "for 'scan_to_body')")
      .def_property_readonly(
          "field_target",
          [](py::object self) {
            return vector_view(self.cast<const HausdorffResult&>().field_target, self);
          },
          "(M,) d~_X(y_j), with fields=True (raw values, before any cap)")
      .def_property_readonly(
          "field_moving",
          [](py::object self) {
            return vector_view(self.cast<const HausdorffResult&>().field_moving, self);
          },
          "(N,) d~_Y(x_i) of every moving point, with fields=True (raw values, before any cap)")
      .def_property_readonly(
          "gradient",
          [](py::object self) {
            return matrix_view(self.cast<const HausdorffResult&>().gradient_points, self);
          },
          "(N, d) d rho / d x_i, with gradient=True")
      .def_property_readonly(
          "gradient_volumes",
          [](py::object self) {
            return vector_view(self.cast<const HausdorffResult&>().gradient_volumes, self);
          },
          "(N,) d rho / d V_i, with gradient_volumes=True")
      .def_property_readonly(
          "gradient_target",
          [](py::object self) {
            return matrix_view(self.cast<const HausdorffResult&>().gradient_target, self);
          },
          "(M, d) d rho / d y_j, with gradient_target=True")
      .def_readonly("kernel_evaluations", &HausdorffResult::kernel_evaluations)
      .def_readonly("seconds", &HausdorffResult::seconds, "wall time of the evaluation (C++)")
      .def("__repr__", &result_repr);

  py::class_<HausdorffTarget>(m, "Target", "A target cloud prepared for repeated evaluations.")
      .def(py::init(&make_target), py::arg("Y").noconvert(), py::arg("VY").noconvert(),
           py::kw_only(), py::arg("alpha"), py::arg("beta"), py::arg("gamma"), py::arg("eps"),
           py::arg("method"), py::arg("tol"), py::arg("threads"))
      .def("evaluate", &evaluate, py::arg("X").noconvert(), py::arg("VX").noconvert(),
           py::kw_only(), py::arg("fields"), py::arg("gradient"), py::arg("gradient_volumes"),
           py::arg("gradient_target"), py::arg("distance") = "symmetric", py::arg("cap") = 0.0,
           py::arg("cap_q") = 4.0, py::arg("camera_mask") = py::none(), py::arg("hessian") = false)
      .def("hessian_product", &hessian_product, py::arg("at"), py::arg("V").noconvert(),
           py::kw_only(), py::arg("part") = "full")
      .def_property_readonly("size", [](const HausdorffTarget& t) { return t.cloud().size(); })
      .def_property_readonly("dim", [](const HausdorffTarget& t) { return t.cloud().dim(); })
      .def_property_readonly("total_volume",
                             [](const HausdorffTarget& t) { return t.cloud().total_volume(); });

  // Test hook for the no-copy promise: the address of the data the argument caster hands to
  // C++ for an Array argument (the same caster as every cloud argument).
  m.def(
      "_data_address", [](const Array& a) { return reinterpret_cast<std::uintptr_t>(a.data()); },
      py::arg("a").noconvert());
}

}  // namespace softhd::python

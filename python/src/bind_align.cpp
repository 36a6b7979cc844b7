// softhd._core.align: the pose of a scan (softhd/scan/align.hpp), returned as a dict.

#include <cstdint>
#include <limits>
#include <string>

#include "common.hpp"
#include "softhd/error.hpp"
#include "softhd/scan/align.hpp"

namespace softhd::python {

namespace {

py::dict align_clouds(const Array& body, const std::optional<Array>& body_volumes,
                      const Array& scan, bool similarity, double scale_min, double scale_max,
                      const std::string& distance, double cap, std::optional<double> eps,
                      double alpha, double beta, double gamma, bool global_start,
                      const std::optional<Array>& initial, int rotations, int refine_points,
                      double inlier, int threads, const std::string& score, int keep,
                      const std::optional<Array>& fixture, const std::optional<Array>& table,
                      const std::optional<Array>& clamp,
                      const std::optional<py::array_t<std::int64_t>>& body_triangles) {
  check_cloud(body, body_volumes, "body");
  check_cloud(scan, std::nullopt, "scan");
  scan::AlignOptions o;
  o.kind = similarity ? scan::PoseKind::similarity : scan::PoseKind::rigid;
  o.scale_min = scale_min;
  o.scale_max = scale_max;
  o.form.sides = sides_from_string(distance);
  o.form.cap.c = cap;
  o.distance.params.alpha = alpha;
  o.distance.params.beta = beta;
  o.distance.params.gamma = gamma;
  o.global_start = global_start;
  o.rotations = rotations;
  o.score = scan::candidate_score_from_string(score);
  o.keep = keep;
  o.refine_points = refine_points;
  o.inlier_distance = inlier;
  o.threads = threads;
  if (initial) {
    if (initial->ndim() != 2 || initial->shape(0) != 4 || initial->shape(1) != 4)
      throw InvalidArgument("initial must be a (4, 4) array");
    o.initial = scan::Pose::from_matrix(Eigen::Map<const RowMatrix>(initial->data(), 4, 4));
  }
  // A plane as 4 numbers (n1, n2, n3, offset): n·x = offset.
  const auto plane = [](const Array& a, const char* name) {
    if (a.ndim() != 1 || a.shape(0) != 4)
      throw InvalidArgument(std::string(name) + " must be 4 numbers (the normal, the offset)");
    return Eigen::Vector4d(a.data()[0], a.data()[1], a.data()[2], a.data()[3]);
  };
  if (fixture) {
    const Eigen::Vector4d f = plane(*fixture, "fixture");
    o.fixture = scan::Fixture{f.head<3>(), f[3]};
  }
  if (clamp) {
    if (clamp->ndim() != 1 || clamp->shape(0) != 6)
      throw InvalidArgument(
          "clamp must be 6 numbers (its direction in the body's frame, then in "
          "the scan's)");
    if (!o.fixture) throw InvalidArgument("clamp is the fixture's clamp side: give fixture");
    const Eigen::Map<const Eigen::Matrix<double, 6, 1>> c(clamp->data());
    o.fixture->clamp = c.head<3>();
    o.fixture->clamp_seen = c.tail<3>();
  }
  if (table) {
    const Eigen::Vector4d f = plane(*table, "table");
    o.table = scan::Plane{Eigen::VectorXd(f.head<3>()), f[3], 0};
  }
  if (body_triangles) {  // ids into the body's rows (their range checked by align)
    const auto& t = *body_triangles;
    if (t.ndim() != 2 || t.shape(1) != 3)
      throw InvalidArgument("body_triangles must be a (T, 3) integer array");
    o.body_triangles.resize(t.shape(0), 3);
    auto v = t.unchecked<2>();
    for (py::ssize_t i = 0; i < t.shape(0); ++i)
      for (py::ssize_t c = 0; c < 3; ++c) {
        const std::int64_t k = v(i, c);
        if (k < 0 || k > std::numeric_limits<int>::max())
          throw InvalidArgument("body_triangles: a triangle names point " + std::to_string(k) +
                                ", outside 0.." + std::to_string(body.shape(0) - 1));
        o.body_triangles(i, c) = static_cast<int>(k);
      }
  }
  const PointCloud B = make_cloud(body, body_volumes), S = make_cloud(scan, std::nullopt);
  o.distance.params.epsilon = eps ? *eps : 1e-3 * scan::body_size(B);  // None: L/1000
  scan::AlignSummary s;
  {
    py::gil_scoped_release release;
    s = scan::align(B, S, o);
  }
  py::dict d;
  const RowMatrix m = s.pose.matrix();
  d["matrix"] = to_numpy(m);
  const Eigen::Matrix<double, 7, 1> x = s.pose.twist();
  d["twist"] = to_numpy(RowMatrix(x.transpose()));
  d["scale"] = s.pose.s;
  d["rho"] = s.rho;
  d["overlap"] = s.overlap;
  d["inlier_distance"] = s.inlier_distance;
  d["rmse"] = s.rmse;
  d["residuals"] = to_numpy(RowMatrix(s.residuals.transpose()));
  d["status"] = scan::to_string(s.status);
  d["iterations"] = s.iterations;
  d["seconds"] = s.seconds;
  d["starts"] = s.starts;
  d["candidates"] = s.candidates;
  d["refine_points"] = py::make_tuple(s.refine_body_points, s.refine_scan_points);
  return d;
}

}  // namespace

void bind_align(py::module_& m) {
  m.def("align", &align_clouds, py::arg("body").noconvert(), py::arg("body_volumes").noconvert(),
        py::arg("scan").noconvert(), py::kw_only(), py::arg("similarity"), py::arg("scale_min"),
        py::arg("scale_max"), py::arg("distance"), py::arg("cap"), py::arg("eps"), py::arg("alpha"),
        py::arg("beta"), py::arg("gamma"), py::arg("global_start"), py::arg("initial"),
        py::arg("rotations"), py::arg("refine_points"), py::arg("inlier"), py::arg("threads"),
        py::arg("score"), py::arg("keep"), py::arg("fixture"), py::arg("table"), py::arg("clamp"),
        py::arg("body_triangles"));
}

}  // namespace softhd::python

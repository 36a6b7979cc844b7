// softhd._core scan clean-up, surface weights and visibility (softhd/scan/cleanup.hpp,
// softhd/scan/surface_weights.hpp, softhd/scan/visibility.hpp): clouds in, kept indices, areas
// or masks out.

#include <cstdint>
#include <vector>

#include "common.hpp"
#include "softhd/error.hpp"
#include "softhd/scan/cleanup.hpp"
#include "softhd/scan/surface_weights.hpp"
#include "softhd/scan/visibility.hpp"

namespace softhd::python {

namespace {

py::array_t<std::int64_t> to_indices(const std::vector<Eigen::Index>& kept) {
  py::array_t<std::int64_t> out(static_cast<py::ssize_t>(kept.size()));
  std::int64_t* p = out.mutable_data();
  for (std::size_t i = 0; i < kept.size(); ++i) p[i] = static_cast<std::int64_t>(kept[i]);
  return out;
}

Eigen::VectorXd to_vector(const Array& a, const char* name) {
  if (a.ndim() != 1) throw InvalidArgument(std::string(name) + " must be a 1-D array");
  return Eigen::Map<const Eigen::VectorXd>(a.data(), a.shape(0));
}

py::array_t<std::int64_t> crop(const Array& points, const Array& lower, const Array& upper,
                               double margin) {
  check_cloud(points, std::nullopt, "points");
  const Eigen::VectorXd lo = to_vector(lower, "lower"), hi = to_vector(upper, "upper");
  std::vector<Eigen::Index> kept;
  {
    py::gil_scoped_release release;
    kept = scan::crop_to_box(make_cloud(points, std::nullopt), lo, hi, margin);
  }
  return to_indices(kept);
}

py::array_t<std::int64_t> outliers(const Array& points, int k, double ratio) {
  check_cloud(points, std::nullopt, "points");
  std::vector<Eigen::Index> kept;
  {
    py::gil_scoped_release release;
    kept = scan::remove_statistical_outliers(make_cloud(points, std::nullopt), k, ratio);
  }
  return to_indices(kept);
}

scan::PlaneRemoval plane_options(double distance, int iterations, double min_fraction,
                                 std::uint64_t seed) {
  scan::PlaneRemoval options;
  options.distance = distance;
  options.iterations = iterations;
  options.min_fraction = min_fraction;
  options.seed = seed;
  return options;
}

py::array_t<std::int64_t> plane(const Array& points, double distance, int iterations,
                                double min_fraction, std::uint64_t seed) {
  check_cloud(points, std::nullopt, "points");
  const scan::PlaneRemoval options = plane_options(distance, iterations, min_fraction, seed);
  std::vector<Eigen::Index> kept;
  {
    py::gil_scoped_release release;
    kept = scan::remove_dominant_plane(make_cloud(points, std::nullopt), options);
  }
  return to_indices(kept);
}

py::dict find_plane(const Array& points, double distance, int iterations, double min_fraction,
                    std::uint64_t seed) {
  check_cloud(points, std::nullopt, "points");
  const scan::PlaneRemoval options = plane_options(distance, iterations, min_fraction, seed);
  scan::Plane found;
  {
    py::gil_scoped_release release;
    found = scan::find_dominant_plane(make_cloud(points, std::nullopt), options);
  }
  py::dict d;
  py::array_t<double> normal(found.normal.size());
  Eigen::Map<Eigen::VectorXd>(normal.mutable_data(), found.normal.size()) = found.normal;
  d["normal"] = normal;
  d["offset"] = found.offset;
  d["inliers"] = found.inliers;
  return d;
}

py::array_t<double> areas(const Array& points, const std::string& method, int neighbours) {
  check_cloud(points, std::nullopt, "points");
  const scan::AreaEstimate estimate = scan::area_estimate_from_string(method);
  Eigen::VectorXd a;
  {
    py::gil_scoped_release release;
    a = scan::area_weights(make_cloud(points, std::nullopt), estimate, neighbours);
  }
  py::array_t<double> out(a.size());
  Eigen::Map<Eigen::VectorXd>(out.mutable_data(), a.size()) = a;
  return out;
}

// The surface of (N, 3) points and (T, 3) int64 triangles over them (ids checked by the
// library: InvalidArgument naming the range).
TriangleSurface surface_of(const Array& points, const py::array_t<std::int64_t>& triangles) {
  if (points.ndim() != 2 || points.shape(1) != 3)
    throw InvalidArgument("visible_points: points must be an (N, 3) array");
  if (triangles.ndim() != 2 || triangles.shape(1) != 3)
    throw InvalidArgument("visible_points: triangles must be a (T, 3) integer array");
  TriangleSurface s;
  s.points = Eigen::Map<const RowMatrix>(points.data(), points.shape(0), 3);
  s.triangles.resize(triangles.shape(0), 3);
  auto t = triangles.unchecked<2>();
  for (py::ssize_t i = 0; i < triangles.shape(0); ++i)
    for (py::ssize_t c = 0; c < 3; ++c) {
      const std::int64_t k = t(i, c);
      if (k < 0 || k >= points.shape(0))
        throw InvalidArgument("visible_points: a triangle names point " + std::to_string(k) +
                              ", outside 0.." + std::to_string(points.shape(0) - 1));
      s.triangles(i, c) = static_cast<int>(k);
    }
  return s;
}

py::array_t<bool> visible(const Array& points, const py::array_t<std::int64_t>& triangles,
                          const Array& camera, double tolerance) {
  const TriangleSurface s = surface_of(points, triangles);
  if (camera.ndim() != 1 || camera.shape(0) != 3)
    throw InvalidArgument("visible_points: camera must be a 3-vector");
  const Eigen::Vector3d c(camera.data()[0], camera.data()[1], camera.data()[2]);
  Eigen::Array<bool, Eigen::Dynamic, 1> seen;
  {
    py::gil_scoped_release release;
    seen = scan::visible_points(s, c, tolerance);
  }
  py::array_t<bool> out(seen.size());
  for (Eigen::Index i = 0; i < seen.size(); ++i) out.mutable_data()[i] = seen[i];
  return out;
}

}  // namespace

void bind_scan(py::module_& m) {
  m.def("crop_to_box", &crop, py::arg("points").noconvert(), py::arg("lower").noconvert(),
        py::arg("upper").noconvert(), py::arg("margin"));
  m.def("remove_statistical_outliers", &outliers, py::arg("points").noconvert(), py::arg("k"),
        py::arg("ratio"));
  m.def("remove_dominant_plane", &plane, py::arg("points").noconvert(), py::arg("distance"),
        py::arg("iterations"), py::arg("min_fraction"), py::arg("seed"));
  m.def("find_dominant_plane", &find_plane, py::arg("points").noconvert(), py::arg("distance"),
        py::arg("iterations"), py::arg("min_fraction"), py::arg("seed"));
  m.def("area_weights", &areas, py::arg("points").noconvert(), py::arg("method"),
        py::arg("neighbours"));
  m.def("visible_points", &visible, py::arg("points").noconvert(), py::arg("triangles"),
        py::arg("camera").noconvert(), py::arg("tolerance"));
}

}  // namespace softhd::python

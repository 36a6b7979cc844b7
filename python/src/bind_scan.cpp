// softhd._core scan clean-up and surface weights (softhd/scan/cleanup.hpp,
// softhd/scan/surface_weights.hpp): clouds in, kept indices or areas out.

#include <cstdint>
#include <vector>

#include "common.hpp"
#include "softhd/error.hpp"
#include "softhd/scan/cleanup.hpp"
#include "softhd/scan/surface_weights.hpp"

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

py::array_t<std::int64_t> plane(const Array& points, double distance, int iterations,
                                double min_fraction, std::uint64_t seed) {
  check_cloud(points, std::nullopt, "points");
  scan::PlaneRemoval options;
  options.distance = distance;
  options.iterations = iterations;
  options.min_fraction = min_fraction;
  options.seed = seed;
  std::vector<Eigen::Index> kept;
  {
    py::gil_scoped_release release;
    kept = scan::remove_dominant_plane(make_cloud(points, std::nullopt), options);
  }
  return to_indices(kept);
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

}  // namespace

void bind_scan(py::module_& m) {
  m.def("crop_to_box", &crop, py::arg("points").noconvert(), py::arg("lower").noconvert(),
        py::arg("upper").noconvert(), py::arg("margin"));
  m.def("remove_statistical_outliers", &outliers, py::arg("points").noconvert(), py::arg("k"),
        py::arg("ratio"));
  m.def("remove_dominant_plane", &plane, py::arg("points").noconvert(), py::arg("distance"),
        py::arg("iterations"), py::arg("min_fraction"), py::arg("seed"));
  m.def("area_weights", &areas, py::arg("points").noconvert(), py::arg("method"),
        py::arg("neighbours"));
}

}  // namespace softhd::python

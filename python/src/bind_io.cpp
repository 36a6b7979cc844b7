// softhd._core.read_cloud / write_cloud: the library's cloud files (text, PLY; PCD read only).

#include <pybind11/stl.h>

#include "common.hpp"
#include "softhd/io/cloud_io.hpp"

namespace softhd::python {

namespace {

py::tuple read(const std::string& path, int dim) {
  std::optional<PointCloud> cloud;
  std::vector<std::string> notes;
  {
    py::gil_scoped_release release;
    cloud.emplace(read_cloud(path, dim, &notes));
  }
  py::array_t<double> volumes(cloud->size());
  Eigen::Map<Eigen::VectorXd>(volumes.mutable_data(), cloud->size()) = cloud->volumes();
  return py::make_tuple(to_numpy(cloud->points()), volumes, notes);
}

void write(const std::string& path, const Array& points, const std::optional<Array>& volumes) {
  check_cloud(points, volumes, "points");
  py::gil_scoped_release release;
  write_cloud(path, make_cloud(points, volumes));
}

}  // namespace

void bind_io(py::module_& m) {
  m.def("read_cloud", &read, py::arg("path"), py::arg("dim") = 0);
  m.def("write_cloud", &write, py::arg("path"), py::arg("points").noconvert(),
        py::arg("volumes").noconvert() = py::none());
}

}  // namespace softhd::python

#include "common.hpp"

#include "softhd/error.hpp"
#include "softhd/parallel.hpp"

namespace softhd::python {

void check_cloud(const Array& points, const std::optional<Array>& volumes,
                 const std::string& name) {
  if (points.ndim() != 2)
    throw InvalidArgument(name + " must be an (N, d) array, got " + std::to_string(points.ndim()) +
                          " dimensions");
  if (volumes) {
    if (volumes->ndim() != 1 || volumes->shape(0) != points.shape(0))
      throw InvalidArgument("the volumes of " + name + " must be an array of N = " +
                            std::to_string(points.shape(0)) + " entries");
  }
}

PointCloud make_cloud(const Array& points, const std::optional<Array>& volumes) {
  const Eigen::Index n = points.shape(0), d = points.shape(1);
  const Eigen::Map<const RowMatrix> P(points.data(), n, d);
  if (!volumes) return PointCloud(Eigen::MatrixXd(P));
  const Eigen::Map<const Eigen::VectorXd> V(volumes->data(), n);
  return PointCloud(Eigen::MatrixXd(P), Eigen::VectorXd(V));
}

py::object matrix_view(const Eigen::MatrixXd& m, py::handle owner) {
  if (m.size() == 0) return py::none();
  const auto s = static_cast<py::ssize_t>(sizeof(double));
  return py::array_t<double>({m.rows(), m.cols()}, {s, s * m.rows()}, m.data(), owner);
}

py::object vector_view(const Eigen::VectorXd& v, py::handle owner) {
  if (v.size() == 0) return py::none();
  return py::array_t<double>({v.size()}, {static_cast<py::ssize_t>(sizeof(double))}, v.data(),
                             owner);
}

py::array_t<double> to_numpy(const RowMatrix& m) {
  py::array_t<double> out({m.rows(), m.cols()});
  Eigen::Map<RowMatrix>(out.mutable_data(), m.rows(), m.cols()) = m;
  return out;
}

ThreadScope::ThreadScope(int threads) : previous_(max_threads()) {
  check_threads(threads);
  if (threads > 0) {
    set_threads(threads);
    changed_ = true;
  }
}

ThreadScope::~ThreadScope() {
  if (changed_) set_threads(previous_);
}

}  // namespace softhd::python

#pragma once
// Shared pieces of the Python bindings (module softhd._core): array types, cloud views,
// thread scopes. The bindings only convert arguments and results; all work is library calls.

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <Eigen/Core>
#include <optional>
#include <string>

#include "softhd/point_cloud.hpp"

namespace softhd::python {

namespace py = pybind11;

/// A C-contiguous float64 NumPy array. Arguments of this type are declared noconvert:
/// pybind11 then passes the caller's array itself (never a converted copy) or raises
/// TypeError; the Python layer (softhd/__init__.py) converts other inputs by its rule.
using Array = py::array_t<double, py::array::c_style>;
/// Row-major (C order) view type of an (N, d) array.
using RowMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

/// Throws InvalidArgument unless `points` is (N, d) and `volumes`, if given, is (N,).
/// `name` names the argument in the message.
void check_cloud(const Array& points, const std::optional<Array>& volumes, const std::string& name);
/// The cloud read in place from the arrays (checked by check_cloud first). Needs no GIL: the
/// PointCloud constructor copies the points once into its structure-of-arrays layout, as it
/// does for any C++ caller.
PointCloud make_cloud(const Array& points, const std::optional<Array>& volumes);
/// A NumPy view (Fortran order) of a column-major matrix kept alive by `owner`; None if empty.
py::object matrix_view(const Eigen::MatrixXd& m, py::handle owner);
/// A NumPy view of a vector kept alive by `owner`; None if empty.
py::object vector_view(const Eigen::VectorXd& v, py::handle owner);
/// A new C-order (rows, cols) array with the entries of the row-major matrix `m`.
py::array_t<double> to_numpy(const RowMatrix& m);

/// Sets the OpenMP threads of the calling thread for its lifetime (0: leave as is) and
/// restores the previous count. Throws InvalidArgument as set_threads (0 to kMaxThreads).
class ThreadScope {
 public:
  explicit ThreadScope(int threads);
  ~ThreadScope();
  ThreadScope(const ThreadScope&) = delete;
  ThreadScope& operator=(const ThreadScope&) = delete;

 private:
  int previous_ = 0;
  bool changed_ = false;
};

void bind_errors(py::module_& m);
/// Installs the interrupt check that lets Ctrl-C stop long calls (KeyboardInterrupt).
void bind_interrupts();
void bind_hausdorff(py::module_& m);
void bind_scan(py::module_& m);
void bind_io(py::module_& m);
void bind_align(py::module_& m);
void bind_mesh(py::module_& m);
void bind_fe(py::module_& m);
void bind_optimise(py::module_& m);

}  // namespace softhd::python

#include "softhd/control/targets.hpp"

#include <cmath>
#include <sstream>
#include <utility>

#include "softhd/error.hpp"
#include "softhd/fe/interpolation.hpp"

namespace softhd {

void ArcMap::validate() const {
  if (!(length > 0.0) || !(thickness > 0.0) || !std::isfinite(length) || !std::isfinite(thickness))
    throw InvalidArgument("arc target: length and thickness must be finite and > 0");
  if (!(angle > 0.0) || !(angle <= 2.0 * M_PI + 1e-12))
    throw InvalidArgument("arc target: angle must be in (0, 2 pi], got " + std::to_string(angle));
  if (!origin.allFinite()) throw InvalidArgument("arc target: the origin must be finite");
  if (!(length / angle > 0.5 * thickness))
    throw InvalidArgument("arc target: the radius length/angle must exceed half the thickness");
}

Eigen::Vector3d ArcMap::operator()(const Eigen::Vector3d& X) const {
  // P = X − origin: T(X) = origin + ((R − z) sin(P1/R), P2, t/2 + R − (R − z) cos(P1/R)).
  const Eigen::Vector3d P = X - origin;
  const double R = length / angle, z = P[2] - 0.5 * thickness;
  return origin + Eigen::Vector3d((R - z) * std::sin(P[0] / R), P[1],
                                  0.5 * thickness + R - (R - z) * std::cos(P[0] / R));
}

double ArcMap::jacobian(const Eigen::Vector3d& X) const {
  return 1.0 - (X[2] - origin[2] - 0.5 * thickness) / (length / angle);  // 1 − z/R
}

PointCloud ArcMap::apply(const PointCloud& reference) const {
  validate();
  if (reference.dim() != 3) throw InvalidArgument("arc target: the cloud must be 3D");
  Eigen::MatrixXd p(reference.size(), 3);
  Eigen::VectorXd v(reference.size());
  for (Eigen::Index i = 0; i < reference.size(); ++i) {
    const Eigen::Vector3d X = reference.points().row(i).transpose();
    p.row(i) = (*this)(X).transpose();
    v[i] = reference.volumes()[i] * jacobian(X);
  }
  return PointCloud(p, v);
}

Eigen::VectorXd ArcMap::displacement(const fe::Mesh& mesh) const {
  validate();
  if (mesh.dim != 3) throw InvalidArgument("arc target: the mesh must be 3D");
  Eigen::VectorXd u(mesh.num_nodes() * 3);
  for (Eigen::Index n = 0; n < mesh.num_nodes(); ++n) {
    const Eigen::Vector3d X = mesh.nodes.row(n).transpose();
    u.segment<3>(3 * n) = (*this)(X)-X;
  }
  return u;
}

NodalMap::NodalMap(fe::Mesh source, const PointCloud& deformed) : source_(std::move(source)) {
  if (deformed.dim() != source_.dim || deformed.size() != source_.num_nodes()) {
    std::ostringstream os;
    os << "manufactured target: the cloud has " << deformed.size() << " points in "
       << deformed.dim() << "D, the mesh it was solved on has " << source_.num_nodes()
       << " nodes in " << source_.dim << "D";
    throw InvalidArgument(os.str());
  }
  u_ = deformed.points() - source_.nodes;
}

Eigen::VectorXd NodalMap::displacement_at(const Eigen::VectorXd& X) const {
  const fe::PointLocator locator(source_);
  return displacements_at(locator, X.transpose()).row(0).transpose();
}

Eigen::MatrixXd NodalMap::displacements_at(const fe::PointLocator& locator,
                                           const Eigen::MatrixXd& X) const {
  // u_T(X) = Σ_a N_a(ξ) (y_a − X_a)
  std::vector<int> outside;
  const Eigen::MatrixXd u = fe::interpolate_nodal(source_, locator, u_, X, &outside);
  if (!outside.empty()) {
    std::ostringstream os;
    os << "manufactured target: the point (" << X.row(outside[0])
       << ") is outside the body the target was solved on";
    throw InvalidArgument(os.str());
  }
  return u;
}

Eigen::VectorXd NodalMap::displacement(const fe::Mesh& mesh) const {
  if (mesh.dim != source_.dim) throw InvalidArgument("manufactured target: dimensions differ");
  const fe::PointLocator locator(source_);
  const Eigen::MatrixXd u = displacements_at(locator, mesh.nodes);  // nodes by dim
  return u.transpose().reshaped();
}

}  // namespace softhd

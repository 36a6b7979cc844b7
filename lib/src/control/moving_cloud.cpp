// The moving cloud u ↦ X(u) of the shape objective (docs/formulation.md §4.3, §8.6, §8.7).

#include "softhd/control/moving_cloud.hpp"

#include <string>

#include "softhd/enum_names.hpp"
#include "softhd/error.hpp"
#include "softhd/fe/cloud.hpp"
#include "softhd/scan/visibility.hpp"

namespace softhd {

namespace {
constexpr auto kParticles = enum_sequence<Particles::boundary>({"nodes", "quadrature", "boundary"});
constexpr auto kVolumes = enum_sequence<ParticleVolumes::deformed>({"reference", "deformed"});

fe::CloudPoints cloud_points(Particles p) {
  return p == Particles::nodes ? fe::CloudPoints::kNodes : fe::CloudPoints::kQuadraturePoints;
}
fe::CloudVolumes cloud_volumes(ParticleVolumes v) {
  return v == ParticleVolumes::reference ? fe::CloudVolumes::kReference
                                         : fe::CloudVolumes::kDeformed;
}
}  // namespace

std::string to_string(Particles p) { return enum_name(kParticles, p); }
std::string to_string(ParticleVolumes v) { return enum_name(kVolumes, v); }
Particles particles_from_string(const std::string& name) {
  return enum_from_name(kParticles, name, "particles");
}
ParticleVolumes particle_volumes_from_string(const std::string& name) {
  return enum_from_name(kVolumes, name, "volumes");
}

MovingCloud::MovingCloud(const fe::Assembler& assembler, Particles particles,
                         ParticleVolumes volumes, bool boundary)
    : assembler_(assembler), particles_(particles), volumes_(volumes) {
  const fe::Mesh& mesh = assembler.mesh();
  if (boundary || particles == Particles::boundary) facets_ = fe::boundary_facets(mesh);
  if (particles == Particles::quadrature) return;
  // Clamped nodes (no free dof) never move.
  const int dim = mesh.dim;
  const bool all = particles == Particles::nodes;
  const Eigen::Index N = all ? mesh.num_nodes() : Eigen::Index(facets_.nodes.size());
  free_points_.setConstant(N, false);
  for (Eigen::Index i = 0; i < N; ++i) {
    const Eigen::Index n = all ? i : facets_.nodes[i];
    for (int c = 0; c < dim; ++c)
      if (assembler.dofs().free_index[n * dim + c] >= 0) free_points_[i] = true;
  }
}

PointCloud MovingCloud::at(const Eigen::VectorXd& u) const {
  if (particles_ == Particles::boundary)
    return fe::boundary_cloud(assembler_.mesh(), facets_, u, cloud_volumes(volumes_));
  return fe::deformed_cloud(assembler_, u, cloud_points(particles_), cloud_volumes(volumes_));
}

Eigen::VectorXd MovingCloud::pullback(const Eigen::VectorXd& u, const HausdorffResult& r) const {
  SOFTHD_ASSERT(r.gradient_points.size() != 0, "the distance's point gradient was not computed");
  SOFTHD_ASSERT(volumes_ == ParticleVolumes::reference || r.gradient_volumes.size() != 0,
                "the distance's volume gradient was not computed (deformed volumes)");
  if (particles_ == Particles::boundary)
    return fe::boundary_cloud_pullback(assembler_.mesh(), facets_, u, cloud_volumes(volumes_),
                                       r.gradient_points, r.gradient_volumes);
  return fe::cloud_pullback(assembler_, u, cloud_points(particles_), cloud_volumes(volumes_),
                            r.gradient_points, r.gradient_volumes);
}

Eigen::MatrixXd MovingCloud::push_forward(const Eigen::VectorXd& w) const {
  const fe::Mesh& mesh = assembler_.mesh();
  const int dim = mesh.dim;
  if (volumes_ != ParticleVolumes::reference)
    throw InvalidArgument("volumes: the points' directions (push_forward) need reference volumes");
  if (w.size() != mesh.num_nodes() * dim)
    throw InvalidArgument("push_forward: w has " + std::to_string(w.size()) +
                          " entries, expected " + std::to_string(mesh.num_nodes() * dim));
  const Eigen::MatrixXd W = w.reshaped(dim, mesh.num_nodes()).transpose();  // nodes by dim
  if (particles_ == Particles::nodes) return W;                             // x_i = X_i + u_i
  if (particles_ == Particles::boundary) {  // x_k = X_{n_k} + u_{n_k}
    Eigen::MatrixXd V(static_cast<Eigen::Index>(facets_.nodes.size()), dim);
    for (Eigen::Index k = 0; k < V.rows(); ++k) V.row(k) = W.row(facets_.nodes[k]);
    return V;
  }
  const fe::ReferenceGeometry& g = assembler_.geometry();  // x_q = Σ_a N_a(ξ_q) (X_a + u_a)
  const int nq = g.points_per_element(), nen = mesh.nodes_per_element();
  Eigen::MatrixXd V = Eigen::MatrixXd::Zero(mesh.num_elements() * nq, dim);
  for (Eigen::Index e = 0; e < mesh.num_elements(); ++e)
    for (int q = 0; q < nq; ++q)
      for (int a = 0; a < nen; ++a)
        V.row(e * nq + q) += g.shape_values()(q, a) * W.row(mesh.elements(e, a));
  return V;
}

Eigen::Array<bool, Eigen::Dynamic, 1> MovingCloud::visible_from(
    const Eigen::VectorXd& u, const Eigen::Vector3d& camera) const {
  SOFTHD_ASSERT(!facets_.nodes.empty(), "visible_from needs the boundary facets");
  const fe::Mesh& mesh = assembler_.mesh();
  const Eigen::Array<bool, Eigen::Dynamic, 1> seen =
      scan::visible_points(fe::boundary_surface(mesh, facets_, u), camera);
  if (!seen.any())
    throw InvalidArgument("distance visible: the camera sees no boundary point of the body");
  if (particles_ == Particles::boundary) return seen;
  Eigen::Array<bool, Eigen::Dynamic, 1> mask;
  mask.setConstant(mesh.num_nodes(), false);
  for (size_t k = 0; k < facets_.nodes.size(); ++k)
    mask[facets_.nodes[k]] = seen[static_cast<Eigen::Index>(k)];
  return mask;
}

}  // namespace softhd

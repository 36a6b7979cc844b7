#pragma once
/// \file moving_cloud.hpp
/// The moving cloud of the shape objective (docs/formulation.md §4.3, §8.6, §8.7): the points of
/// the body deformed by a displacement u — its nodes, its quadrature points, or its boundary
/// nodes — with reference or deformed volumes; the pull-back of a distance gradient to ∂/∂u;
/// and the body's points a camera sees (the visible distance's mask). The first map of the
/// objective's chain u ↦ X(u) ↦ Q_ξ(X(u)) (the pose map, scan/pose_map.hpp, is the second).

#include <Eigen/Core>
#include <string>

#include "softhd/fe/assembly.hpp"
#include "softhd/fe/boundary.hpp"
#include "softhd/hausdorff.hpp"
#include "softhd/point_cloud.hpp"

namespace softhd {

/// Which points of the deformed body form the moving cloud.
enum class Particles {
  nodes,       ///< the mesh nodes
  quadrature,  ///< the quadrature points
  /// the boundary nodes (3D): a surface target's moving cloud, the volumes the lumped facet
  /// areas (reference, or deformed: current), docs/formulation.md §8.6
  boundary,
};
/// Volumes of the moving cloud: fixed reference volumes or the deformed ones.
enum class ParticleVolumes { reference, deformed };

/// "nodes", "quadrature" or "boundary".
std::string to_string(Particles p);
/// "reference" or "deformed".
std::string to_string(ParticleVolumes v);
Particles particles_from_string(const std::string& name);  ///< "nodes"/"quadrature"/"boundary"
ParticleVolumes particle_volumes_from_string(const std::string& name);  ///< "reference"/"deformed"

/// u ↦ X(u) for one body. The assembler must outlive it.
class MovingCloud {
 public:
  /// The cloud of `particles` with `volumes` on the assembler's body; `boundary` keeps the
  /// body's boundary facets (needed by Particles::boundary and by visible_from; 3D only, the
  /// caller checks the dimension).
  MovingCloud(const fe::Assembler& assembler, Particles particles, ParticleVolumes volumes,
              bool boundary);

  Particles particles() const { return particles_; }    ///< which points
  ParticleVolumes volumes() const { return volumes_; }  ///< which volumes
  /// X(u) for a displacement u (num_dofs entries).
  PointCloud at(const Eigen::VectorXd& u) const;
  /// ∂f/∂u (num_dofs) from the gradients of f w.r.t. X(u)'s positions (r.gradient_points)
  /// and, with deformed volumes, its volumes (r.gradient_volumes). Throws InternalError if a
  /// gradient it needs was not computed.
  Eigen::VectorXd pullback(const Eigen::VectorXd& u, const HausdorffResult& r) const;
  /// The points' directions V = (∂X/∂u) w (N by dim) for a displacement direction w (num_dofs
  /// entries), the transpose of pullback's position part: X(u) is affine in u, so for nodes
  /// V_i = w_i, for quadrature points V_q = Σ_a N_a(ξ_q) w_a, for boundary nodes V_k = w_{n_k}.
  /// Throws InvalidArgument for deformed volumes (they move with u too) or a w of the wrong size.
  Eigen::MatrixXd push_forward(const Eigen::VectorXd& w) const;
  /// The points with a free dof (the others never move: their gradients can be skipped);
  /// empty for quadrature points.
  const Eigen::Array<bool, Eigen::Dynamic, 1>& free_points() const { return free_points_; }
  /// The moving points a camera at `camera` (body frame) sees on the boundary deformed by u:
  /// the cloud's own points for boundary particles, the boundary nodes among the nodes for
  /// node particles (docs/formulation.md §8.7). Needs `boundary` at construction. Throws
  /// InvalidArgument if the camera sees no boundary point.
  Eigen::Array<bool, Eigen::Dynamic, 1> visible_from(const Eigen::VectorXd& u,
                                                     const Eigen::Vector3d& camera) const;

 private:
  const fe::Assembler& assembler_;
  Particles particles_;
  ParticleVolumes volumes_;
  fe::BoundaryFacets facets_;
  Eigen::Array<bool, Eigen::Dynamic, 1> free_points_;
};

}  // namespace softhd

#pragma once
/// \file pose_map.hpp
/// The pose of a moving cloud as one map of a twist (docs/formulation.md §8.4, §8.5, §8.10):
///
///     Q_ξ = T_ξ ∘ Q₀,   T_ξ(z) = c + e^σ exp([ω]×)(z − c) + v,   ξ = (ω, v[, σ]),
///
/// a start pose Q₀ followed by a twist about a fixed centre c. `align` steps its pose by it
/// (ξ about the moved cloud's centroid, then Q₀ ← Q_ξ); the shape objective maps its moving
/// cloud into a camera-frame target by it, with the twist as optimisation variables. The
/// derivatives a gradient needs are here too, written once: the twist gradient and the
/// pull-back to the unmoved points.

#include <Eigen/Core>
#include <string>

#include "softhd/point_cloud.hpp"
#include "softhd/scan/pose.hpp"

namespace softhd::scan {

/// What a pose may change: a rigid motion (ξ = (ω, v), 6 variables) or a similarity
/// (ξ = (ω, v, σ), 7, σ = log of the scale change).
enum class PoseKind { rigid, similarity };
/// "rigid" / "similarity".
std::string to_string(PoseKind kind);
/// The PoseKind named "rigid" or "similarity"; throws InvalidArgument naming `align`.
PoseKind pose_kind_from_string(const std::string& name);

/// Q_ξ = T_ξ ∘ Q₀ for twists ξ about the centre c (see the file's comment). Cheap to copy.
class PoseMap {
 public:
  /// The map from the start pose Q₀ (applied first), the twist's centre c and the kind.
  PoseMap(const Pose& start, const Eigen::Vector3d& centre, PoseKind kind);

  /// The number of twist variables: 6 (rigid) or 7 (similarity).
  int variables() const { return kind_ == PoseKind::similarity ? 7 : 6; }
  PoseKind kind() const { return kind_; }                    ///< rigid or similarity
  const Pose& start() const { return start_; }               ///< Q₀
  const Eigen::Vector3d& centre() const { return centre_; }  ///< c

  /// ξ itself, or zeros for an empty ξ. Throws InvalidArgument for a ξ of another size
  /// ("pose twist has N values, expected 6") or not finite: the check of a ξ from a caller.
  /// The members below take an empty ξ as zero and check its size, not its values.
  Eigen::VectorXd checked(const Eigen::VectorXd& xi) const;
  /// Q_ξ: R = E R₀, s = e^σ s₀, t = c + e^σ E (t₀ − c) + v with E = exp([ω]×).
  Pose at(const Eigen::VectorXd& xi) const;
  /// The twist ξ with at(ξ) = Q, the inverse of at: E = R R₀ᵀ, ω = log E, σ = log(s/s₀)
  /// (similarity; rigid: ignored), v = t − c − e^σ E (t₀ − c).
  Eigen::VectorXd twist_of(const Pose& Q) const;
  /// The cloud moved by Q_ξ: points Q_ξ(x_i), volumes unchanged (ρ̃ uses V_i/|X|).
  PointCloud apply(const PointCloud& cloud, const Eigen::VectorXd& xi) const;

  /// ∂f/∂ξ from g_i = ∂f/∂x'_i at the moved points x'_i = Q_ξ(x_i) (rows of `moved`, `g`),
  /// with y_i = x'_i − c − v:
  ///   ∂f/∂v = Σ g_i,   ∂f/∂ω = J_l(ω)ᵀ Σ y_i × g_i,   ∂f/∂σ = Σ y_i·g_i
  /// (J_l the left Jacobian of exp, rotation_left_jacobian).
  Eigen::VectorXd twist_gradient(const Eigen::MatrixXd& moved, const Eigen::MatrixXd& g,
                                 const Eigen::VectorXd& xi) const;
  /// ∂f/∂x_i = s R_ξᵀ g_i: the gradient at the moved points pulled back to the unmoved ones
  /// (rows of `g`), with s, R those of Q_ξ.
  Eigen::MatrixXd pullback(const Eigen::MatrixXd& g, const Eigen::VectorXd& xi) const;

 private:
  Eigen::VectorXd sized(const Eigen::VectorXd& xi) const;  // empty: zeros; size checked
  Pose start_;
  Eigen::Vector3d centre_;
  PoseKind kind_;
};

}  // namespace softhd::scan

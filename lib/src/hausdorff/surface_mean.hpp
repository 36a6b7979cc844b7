#pragma once
// The directed mean over a scan's surface with its points moving (internal; docs/formulation.md
// §2.8, "A scan's surface against the body's cells", and §8.11, the pose by variable projection):
// the gradient of A^4 = (1/W) Σ_j w_j d̃_X(y_j)^4 with respect to the points y_j, the body X and
// the weights fixed,
//
//     ∂A^4/∂y_j = (4 w_j / W) d̃_j³ ∂d̃/∂J ∂J/∂y_j,   ∂d̃/∂J = −(d̃_j + ε)^5 / (4 |Ω_X|).

#include <Eigen/Core>

#include "body_integral.hpp"
#include "cell_distance.hpp"

namespace softhd::detail {

/// A^4 of directed_point_mean (the same value) and, into *point_gradient (M by 3, when not
/// null), ∂A^4/∂y_j for each row y_j of `points`. InvalidArgument as directed_point_mean.
OuterMean directed_point_mean_moving(const Eigen::MatrixXd& points, const Eigen::VectorXd& weights,
                                     const BodyIntegral& source_j, double source_volume,
                                     double epsilon, Eigen::MatrixXd* point_gradient);

}  // namespace softhd::detail

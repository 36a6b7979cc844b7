#pragma once
/// \file surface_weights.hpp
/// Per-point area weights for a surface scan that has none (docs/formulation.md §8), so that
/// a density that falls with distance from the camera does not weigh the near side more.

#include <Eigen/Core>

#include "softhd/point_cloud.hpp"

namespace softhd::scan {

/// How the areas are estimated.
enum class AreaEstimate {
  knn,       ///< π r_k² / k, r_k the distance to the k-th nearest neighbour (k = `neighbours`)
  delaunay,  ///< a third of the areas of the Delaunay triangles of the tangent-plane projection
             ///< of each point's neighbourhood that touch it
};

/// The cloud with its volumes replaced by estimated areas (3D points on a surface).
PointCloud with_area_weights(const PointCloud& cloud, AreaEstimate estimate, int neighbours = 12);

}  // namespace softhd::scan

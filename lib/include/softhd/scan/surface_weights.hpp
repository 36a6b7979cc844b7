#pragma once
/// \file surface_weights.hpp
/// Per-point area weights for a surface scan that has none (docs/formulation.md §8.9), so that
/// a density that falls with distance from the camera does not weigh the near side more.
/// 3D clouds are taken as samples of a surface (weights are areas), 2D clouds as samples of a
/// curve (weights are lengths).

#include <Eigen/Core>
#include <string>

#include "softhd/point_cloud.hpp"

namespace softhd::scan {

/// How the areas are estimated, from each point's k nearest neighbours (k = `neighbours`).
enum class AreaEstimate {
  knn,       ///< π r_k² / k (a curve: 2 r_k / k), r_k the distance to the k-th nearest neighbour
  delaunay,  ///< the point's cell in the tangent-plane Voronoi diagram (the dual of the Delaunay
             ///< triangulation) of its 3k nearest neighbours projected on the plane fitted to
             ///< its k nearest, clipped to the square of half-side r_k (a curve: half the gap
             ///< to the nearest neighbour on each side along the tangent line)
};
/// "knn" or "delaunay".
std::string to_string(AreaEstimate estimate);
/// The estimate named `name`; InvalidArgument for any other name, listing the valid ones.
AreaEstimate area_estimate_from_string(const std::string& name);

/// The N estimated areas. Requires `neighbours` from 1 (delaunay: d) to N − 1; throws
/// InvalidArgument naming `neighbours`, or a point whose neighbours all coincide with it.
Eigen::VectorXd area_weights(const PointCloud& cloud, AreaEstimate estimate, int neighbours = 12);

/// The cloud with its volumes replaced by area_weights().
PointCloud with_area_weights(const PointCloud& cloud, AreaEstimate estimate, int neighbours = 12);

}  // namespace softhd::scan

#pragma once
/// \file samplers.hpp
/// Point clouds sampled from simple shapes (docs/formulation.md §1.3): regular and Q2-node grids
/// of a box, uniform random points in a box, uniform points on a sphere or circle.
///
/// The dimension d of the result is the size of `lo`/`hi` (or `center`), 2 or 3.
/// Grid points are ordered with the x index varying fastest, then y, then z.
/// Bad arguments throw softhd::InvalidArgument naming the parameter.

#include <Eigen/Core>
#include <cstdint>

#include "softhd/point_cloud.hpp"

namespace softhd {

/// Cell-centred regular grid of the box [lo, hi]: `counts[k]` cells of width
/// h_k = (hi_k - lo_k) / counts[k] in direction k, one point at the centre of
/// each cell, with volume V = prod_k h_k (so the volumes sum to the box volume).
/// N = prod_k counts[k]. Requires lo < hi componentwise, all finite, and
/// counts >= 1, with lo, hi, counts of the same size 2 or 3.
PointCloud sample_box_grid(const Eigen::VectorXd& lo, const Eigen::VectorXd& hi,
                           const Eigen::VectorXi& counts);

/// The nodes of a structured mesh of the box [lo, hi] with `elements[k]`
/// quadratic Lagrange (Q2) elements in direction k: 2 * elements[k] + 1 equally
/// spaced nodes per direction, the box corners included. The volumes are the
/// lumped Simpson-rule weights: the tensor product of the 1D weights
/// h/6 * (1, 4, 1) of each element of width h, summed over shared nodes, so
/// sum_i V_i f(x_i) is the exact integral over the box of any f that is a
/// cubic in each coordinate separately (and the volumes sum to the box volume).
/// Same argument requirements as sample_box_grid.
PointCloud sample_q2_nodes(const Eigen::VectorXd& lo, const Eigen::VectorXd& hi,
                           const Eigen::VectorXi& elements);

/// `n` points drawn independently and uniformly from the box: lo <= x < hi.
/// Each point has volume |box| / n. Deterministic for a given seed on every
/// platform: the numbers come from std::mt19937_64 seeded with `seed`, one per
/// coordinate in point order (x, y, [z] of point 0, then point 1, ...), each
/// turned into u in [0, 1) from its 53 high bits, and x_k = lo_k + (hi_k - lo_k) u.
/// Requires lo < hi componentwise, all finite, sizes 2 or 3 and equal, n >= 1.
PointCloud sample_uniform_random(const Eigen::VectorXd& lo, const Eigen::VectorXd& hi,
                                 Eigen::Index n, std::uint64_t seed);

/// `n` points drawn independently and uniformly on the sphere (3D) or circle (2D)
/// of `radius` around `center`, each with volume 4 pi r^2 / n (3D) or
/// 2 pi r / n (2D), i.e. the surface measure. 3D: z uniform in [-1, 1) and
/// azimuth uniform in [0, 2 pi) (Archimedes), 2D: angle uniform in [0, 2 pi).
/// The uniform numbers come from std::mt19937_64 as in sample_uniform_random
/// (two per point in 3D, z first; one in 2D); the points then depend only on
/// std::sqrt, std::cos and std::sin. Requires center of size 2 or 3 and
/// finite, radius > 0 and finite, n >= 1.
PointCloud sample_sphere_shell(const Eigen::VectorXd& center, double radius, Eigen::Index n,
                               std::uint64_t seed);

}  // namespace softhd

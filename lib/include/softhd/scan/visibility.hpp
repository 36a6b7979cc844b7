#pragma once
/// \file visibility.hpp
/// Which of a body's boundary points a camera sees (docs/formulation.md §8): the points of the
/// `visible` distance's B_V. io- and fe-free: the body's boundary comes as a triangle surface
/// (fe::boundary_surface builds it from a mesh in a configuration).

#include <Eigen/Core>

#include "softhd/triangle_surface.hpp"

namespace softhd::scan {

/// For every surface point: true if it faces the camera (some incident triangle's outward
/// normal has n·(camera − x) > 0) and the segment from the camera to it meets no triangle
/// before it (up to `tolerance` times the surface's bounding-box diagonal).
Eigen::Array<bool, Eigen::Dynamic, 1> visible_points(const TriangleSurface& surface,
                                                     const Eigen::Vector3d& camera,
                                                     double tolerance = 1e-6);

}  // namespace softhd::scan

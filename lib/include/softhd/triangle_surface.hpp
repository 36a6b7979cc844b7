#pragma once
/// \file triangle_surface.hpp
/// A triangulated surface: the body's boundary as fe::boundary_surface makes it, and what
/// scan::visible_points casts rays against. Plain data, shared by fe/ and scan/.

#include <Eigen/Core>

namespace softhd {

/// A closed triangulated surface: points (N by 3) and triangles over them, outward oriented.
struct TriangleSurface {
  Eigen::MatrixXd points;                           ///< N by 3
  Eigen::Matrix<int, Eigen::Dynamic, 3> triangles;  ///< T by 3 point indices, outward normals
};

}  // namespace softhd

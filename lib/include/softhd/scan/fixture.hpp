#pragma once
/// \file fixture.hpp
/// The fixture a body sits in (docs/formulation.md §8.12): the table it rests on or is clamped
/// above, known in the body's frame. The clean-up finds the same table in the scan's frame
/// (find_dominant_plane), and mapping one onto the other fixes three of the pose's six
/// degrees of freedom: the two tilts (R takes the scan's table normal to the body's) and the
/// height (the offset). What is left is a rotation about the table's normal and a translation
/// along the table. `align` searches and refines over those three only (AlignOptions::fixture).

#include <Eigen/Core>

#include "softhd/scan/cleanup.hpp"
#include "softhd/scan/pose.hpp"

namespace softhd::scan {

/// The table plane in the body's frame, {x : n·x = offset}, n pointing from the table towards
/// the body (the side the body is on). `normal` need not be a unit vector: the plane is
/// n·x = offset as given, normalised by |n|.
struct Fixture {
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  ///< the table's normal (body frame), ≠ 0
  double offset = 0.0;                                ///< n·x on the table (a length × |n|)
  /// Optional, the clamp's side: a direction in the body's frame from its centre towards its
  /// clamped end (the finger clamped at x = 0: (−1, 0, 0)); zero (default): no side given.
  Eigen::Vector3d clamp = Eigen::Vector3d::Zero();
  /// With `clamp`: the direction the clamped end is seen in, in the scan's frame (e.g. the
  /// image's left, (−1, 0, 0) for a camera whose x points right). A pose that turns `clamp`
  /// more than 90° from it, both projected onto the table, is not tried: the side resolves the
  /// half turn about the table's normal that a smooth body's view leaves open.
  Eigen::Vector3d clamp_seen = Eigen::Vector3d::Zero();
  /// Throws InvalidArgument naming `fixture.normal` (zero length, not finite),
  /// `fixture.offset` (not finite), `fixture.clamp` or `fixture.clamp_seen` (not finite, one
  /// zero and the other not, `clamp` along the normal).
  void validate() const;
  bool has_clamp() const { return clamp.squaredNorm() > 0.0; }  ///< a clamp side is given
};

/// The pose's constraint from a fixture and the scan's table: poses P (scan → body) with
/// R n_s = n_b and n_b·t = d_b − d_s (n, d the unit normals and offsets of the two planes),
/// equivalently Q = P⁻¹ with R_Q n_b = n_s and n_s·t_Q = d_s − d_b: every point's height above
/// the table is the same in both frames (docs/formulation.md §8.12).
class FixtureConstraint {
 public:
  /// From the fixture (body frame) and the scan's table (its frame: a 3D Plane of
  /// find_dominant_plane, whose sign is arbitrary), the scan's normal turned towards the side
  /// where most of `scan` (the points left after the table's removal) lies. Throws
  /// InvalidArgument naming `fixture.*` or `table` (not 3D, zero or not finite).
  FixtureConstraint(const Fixture& fixture, const Plane& table, const Eigen::MatrixXd& scan);

  const Eigen::Vector3d& body_normal() const { return nb_; }  ///< n_b (unit)
  const Eigen::Vector3d& scan_normal() const { return ns_; }  ///< n_s (unit, towards the body)
  double body_offset() const { return db_; }                  ///< d_b
  double scan_offset() const { return ds_; }                  ///< d_s

  /// The pose Q (body → scan frame) on the constraint nearest to Q: first rotated about the
  /// moved body centroid `centre` by the smallest rotation taking R_Q n_b to n_s, then moved
  /// along n_s to the right height.
  Pose project(const Pose& Q, const Eigen::Vector3d& centre) const;
  /// The pose Q = Rot(n_s, angle) R₀ (R₀ the smallest rotation taking n_b to n_s) that puts
  /// the body's centroid `body_centre` over the scan's `scan_centre` along the table, at the
  /// constrained height.
  Pose start(double angle, const Eigen::Vector3d& body_centre,
             const Eigen::Vector3d& scan_centre) const;
  /// False if the fixture has a clamp side and Q (body → scan frame) turns `clamp` more than 90°
  /// from `clamp_seen`, both projected onto the scan's table (true without a clamp side).
  bool allows(const Pose& Q) const;
  /// An orthonormal basis (6 × 3) of the twists (L ω, v) in align's scaled variables that keep
  /// the constraint: ω along n_s, v along the table.
  Eigen::MatrixXd tangent() const;
  /// The least-squares pose P (scan → body) on the constraint taking the rows `from` (scan
  /// frame) onto the rows `to` (body frame): a rotation about n_b and a translation along the
  /// table, by the 2D Kabsch fit of the points projected onto the table (the height of every
  /// residual does not depend on them).
  Pose fit(const Eigen::MatrixXd& from, const Eigen::MatrixXd& to) const;

 private:
  Eigen::Vector3d nb_, ns_;
  double db_ = 0.0, ds_ = 0.0;
  Eigen::Vector3d clamp_ = Eigen::Vector3d::Zero(), seen_ = Eigen::Vector3d::Zero();
};

/// An orthonormal basis (6 × 3) of the twists (L ω, v) (align's scaled variables, applied on the
/// left, in the scan's frame) that keep every point's height along the unit normal n: ω along
/// n, v perpendicular to it.
Eigen::MatrixXd table_tangent(const Eigen::Vector3d& n);

/// The smallest rotation taking the unit vector a to the unit vector b (for b = −a: a half
/// turn about an axis perpendicular to a).
Eigen::Matrix3d rotation_between(const Eigen::Vector3d& a, const Eigen::Vector3d& b);

}  // namespace softhd::scan

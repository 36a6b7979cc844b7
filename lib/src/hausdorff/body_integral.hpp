#pragma once
// The continuum inner integral of a body from its boundary surface (internal; the boundary form
// (b′) of docs/formulation.md §2.8):
//
//     J(y) = ∫_Ω (|y − x| + ε)^−α dx
//
// for the solid Ω bounded by a closed, outward-oriented triangle surface, at points y inside,
// outside or on the surface. By the divergence theorem, with G(r) = ∫₀^r u²(u + ε)^−α du and
// F(x) = (x − y) G(r)/r³ (div F = (r + ε)^−α, F bounded at r = 0),
//
//     J(y) = Σ_t h_t ∫_t G(r)/r³ dA,     h_t = n_t·(x − y)   (constant on a flat triangle).
//
// Derivatives (the kernel itself on the boundary; transport theorem for the surface points):
//
//     ∂J/∂y   = −Σ_t n_t ∫_t (r + ε)^−α dA,
//     ∂J/∂x_a =  Σ_{t ∋ a} n_t ∫_t (r + ε)^−α λ_a dA   (λ_a the hat function of point a on t).
//
// Near triangles (|y − c_t| < near_ratio · R_t, c_t the centroid and R_t the largest distance
// from it to a vertex) are integrated in polar coordinates about the foot of y in the
// triangle's plane: the radial integral in closed form, the angle over each edge's wedge by
// composite Gauss–Legendre in u (tan θ = sinh u; a wedge on an edge shared with a coplanar near
// neighbour is left out, the two cancel); the first moment of the kernel, which the
// hat functions need, as a line integral over the edges (∫_t k (x − p) dA = ∮ K₁(r) ν dl,
// K₁(r) = ∫₀^r s k(s) ds). The other triangles by Dunavant's symmetric 16-point rule (degree 8), or
// beyond 4 · near_ratio · R_t Radon's 7-point rule (degree 5); for α ≥ 3.5 its point-charge part
// G∞/r³ (G∞ = G(∞)) is summed exactly instead: the far triangles' solid angles are 4π × the winding
// number minus the near ones' (exact), which needs a closed surface — seen from outside, those
// terms cancel to a J smaller than them by up to 1/(εJ). All pairs: O(points × triangles), or
// with a tolerance τ > 0 (α = 4) a tree over the triangles (the surface's BVH): a cluster far
// from y enters by the second-order Taylor expansion of its kernels about its centre p,
//
//     Σ_t ∫_t n_t·f(x − y) dA ≈ Σ_{m ≤ 2} (1/m!) D^m f(p − y) : Σ_t n_t ⊗ ∫_t (x − p)^⊗m dA,
//
// (the tail f = d H(|d|), H = (G∞ − G)/r³; the solid angle's d/r³; ∂J/∂y's n k(r)), accepted
// when it lies beyond its triangles' near radii and a proved bound of its remainder fits a
// budget (docs/formulation.md §2.8; one traversal per group of nearby consecutive points):
// |J̃ − J| ≤ τ J and ‖∂J̃/∂y − ∂J/∂y‖ ≤ τ ∫_∂Ω k dA against the same rules summed over all
// pairs; in surface_vjp the corner sums' errors add up to at most τ Σ_k |w_k| ∫_∂Ω k(|y_k − x|) dA.

#include <Eigen/Core>
#include <vector>

#include "softhd/triangle_surface.hpp"

namespace softhd::detail {

/// Parameters of BodyIntegral; the constructor validates them (InvalidArgument naming the
/// field).
struct BodyIntegralOptions {
  double epsilon = 1e-3;  ///< ε > 0 of the kernel (r + ε)^−α
  double alpha = 4.0;     ///< α > 0 of the kernel
  /// A triangle is near y (the polar rule) when |y − c_t| < near_ratio · R_t; ≥ 1. The
  /// far rules' largest relative error of J, measured against the box code on 250 points
  /// around the unit cube (faces of 4² to 16² squares): 2.4e-8 at 3, 1.4e-9 at 4, 3.8e-11 at 6
  /// (docs/formulation.md §2.8).
  double near_ratio = 4.0;
  /// Gauss–Legendre points per panel of the angle and edge rules (2 to 64). 12 keeps the
  /// polar rule's relative error of J below ~1e-12 (measured: 10 points 2e-10, 8 points 2e-8).
  int angle_points = 12;
  /// Largest panel of the angle and edge rules in the sinh variable u (> 0): the integrands
  /// are analytic in the strip |Im u| < π/2, so a panel of width ≤ 2 converges geometrically
  /// at a fixed rate, however close y is to an edge.
  double panel_width = 2.0;
  /// τ ∈ [0, 1): 0 sums every triangle (the rules above); > 0 (α = 4 only) takes far clusters
  /// of triangles by their expansions, with |J̃ − J| ≤ τ J and, with the gradient,
  /// ‖g̃ − g‖ ≤ τ ∫_∂Ω (|y − x| + ε)^−4 dA (the sum of the terms' norms, as the tree method's
  /// gradient bound), J and g exact over the triangles a cluster replaces (the rules above
  /// elsewhere; against the all-pairs values the far rules' own error, ≤ ~1e-9 of J at
  /// near_ratio 4, comes on top); proved bounds, checked per point (a point whose check fails
  /// is redone with the budget its own value gives, then over all pairs).
  /// surface_vjp: Σ_{t, a} |error of Σ_k w_k ∫_t k λ_a dA| ≤ τ Σ_k |w_k| ∫_∂Ω k(|y_k − x|) dA.
  double tolerance = 0.0;
  int threads = 0;  ///< OpenMP threads (0: softhd's default, see parallel.hpp)
};

/// G(r) = ∫₀^r u²(u + ε)^−α du, the radial primitive behind J (closed form, or the binomial
/// series below r = ε/4 where the closed form cancels); exposed for the tests.
double radial_g(double r, double epsilon, double alpha);

/// J(y) of the solid a closed triangle surface bounds, and its derivatives.
class BodyIntegral {
 public:
  /// Copies the surface's geometry. Throws InvalidArgument for an invalid option (naming it),
  /// a triangle index out of range, a triangle of zero area, or a surface that is not closed
  /// and consistently oriented (a directed edge without as many reverse ones).
  BodyIntegral(const TriangleSurface& surface, const BodyIntegralOptions& options);

  /// J(y_k) for the rows y_k of `points` (M by 3) into `value` (M); with `grad` non-null also
  /// ∂J/∂y_k (M by 3). With a tolerance, each point's result depends on the points before it in
  /// its block of 64 rows (their values set its budget), not on the threads; consecutive rows
  /// close together (up to 8 within 1/32 of the surface's bounding radius, as a cell's Gauss
  /// points) share one traversal of the tree, so order the rows by place for speed.
  void evaluate(const Eigen::MatrixXd& points, Eigen::VectorXd* value,
                Eigen::MatrixXd* grad = nullptr) const;

  /// The vector–Jacobian product for the surface points: Σ_k w_k ∂J(y_k)/∂x_a for every
  /// surface point a (N by 3), `weights` (M) one per row of `points`. Deterministic for a
  /// fixed thread count.
  Eigen::MatrixXd surface_vjp(const Eigen::MatrixXd& points, const Eigen::VectorXd& weights) const;

  /// Per-triangle geometry (public for the implementation's free functions).
  struct Triangle {
    double v[3][3];  // vertices
    double n[3];     // unit outward normal
    double c[3];     // centroid
    double near2;    // (near_ratio · R_t)²
    // The far rule's 16 points by coordinate and its weights times the area (the vectorised
    // far loops).
    alignas(64) double qx[16];
    double qy[16], qz[16], wq[16];
    // The same for the 7-point rule beyond far2, padded to 8 lanes.
    alignas(64) double cx[8];
    double cy[8], cz[8], cw[8];
    double far2;        // (4 · near_ratio · R_t)²
    double tau[3][3];   // unit edge directions, edge e from v_e to v_{e+1}
    double nu[3][3];    // in-plane outward edge normals, τ_e × n
    double len[3];      // edge lengths
    double glam[3][3];  // in-plane gradients of the hat functions λ_a
    // Across edge e, the coplanar neighbour's index in the same list of triangles (−1: none,
    // or not coplanar): where both are near, their wedges on the edge cancel.
    int twin[3];
  };

  /// A node of the tree: its triangles' moments about p, n-weighted (M) and plain (m):
  /// M0_i = Σ A_t n_i, M1_ij = Σ n_i ∫_t s_j, M2_ijk = Σ n_i ∫_t s_j s_k, m1, m2 likewise,
  /// s = x − p (exact by the 16-point rule).
  struct Cluster {
    double p[3];     // the area-weighted centroid
    double rho;      // the largest |v − p| over its triangles' corners
    double r3;       // √(∫|s|² ∫|s|⁴)/area ≥ ∫|s|³ dA/area, ≤ ρ³
    double reach;    // the largest near radius (near_ratio · R_t) of its triangles
    double area;     // Σ A_t
    double m0[3];    // M0
    double m1[9];    // M1, row-major
    double m2[27];   // M2, [i][j][k]
    double q[3];     // 2 Σ_i M2_iik + Σ_j M2_kjj (the ∂²K contraction)
    double v[3];     // Σ_j M2_ijj
    double tr1;      // Σ_i M1_ii
    double s1[3];    // m1
    double s2[9];    // m2
    double tr2;      // Σ_j m2_jj
    int left;        // −1: a leaf, else the children left and left + 1
    int begin, end;  // its triangles: order_[begin, end)
  };

 private:
  BodyIntegralOptions options_;
  Eigen::Index point_count_ = 0;
  std::vector<Triangle> triangles_;
  std::vector<int> corners_;             // 3 per triangle: the surface point indices
  std::vector<double> rule_x_, rule_w_;  // Gauss–Legendre on [0, 1]
  std::vector<Cluster> clusters_;        // the tree (tolerance > 0), clusters_[0] the root
  std::vector<int> order_;               // triangle ids grouped by leaf
  std::vector<Triangle> ordered_;        // triangles_[order_[j]] (contiguous leaves)
  double total_area_ = 0.0;
  double group_radius_ = 0.0;  // the largest radius of a group of points sharing a traversal

  void evaluate_tree(const Eigen::MatrixXd& points, Eigen::VectorXd* value,
                     Eigen::MatrixXd* grad) const;
  Eigen::MatrixXd surface_vjp_tree(const Eigen::MatrixXd& points,
                                   const Eigen::VectorXd& weights) const;
};

}  // namespace softhd::detail

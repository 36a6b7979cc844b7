#pragma once
// The directed outer mean over the outer body's cells, and the cell-integrated ρ̃ (internal, not
// an option of the distance yet; docs/formulation.md §2.8, "The outer mean in C++"), for
// α = β = 4, γ = 2 (the paper's), and its exact gradient with respect to the nodes of both bodies
// (the default rule only; cell_distance_gradient.cpp):
//
//     A^β = (1/|Ω_Y|) ∫_Ω_Y d̃_X(y)^β dy,   d̃_X(y) = (J_X(y)/|Ω_X|)^(−1/α) − ε,
//     ρ̃ = ((A^γ + B^γ)/2)^(1/γ)   (B likewise, the bodies exchanged),
//
// J_X(y) = ∫_Ω_X (|y − x| + ε)^−α dx by BodyIntegral from X's boundary triangles, sd_X(y) the
// signed distance to them (SurfaceDistance), |Ω_X| by the divergence theorem on them.
//
// Per outer cell (trilinear hexahedron): J at its 2×2×2 Gauss points (the samples s), and the
// factor f_s = log(J_s / P_ε(sd_s)), P_ε the half-space profile. A cell far from the surface
// (CellDistanceOptions::near_factor): the 2×2×2 Gauss rule (weights w_q det J) with J_s, or
// farther (corner_factor) a rule of the same degree with J at its corners and centre. Otherwise
// J(y) = P_ε(sd(y)) · exp(f(y)), f trilinear in reference coordinates through the 8 samples
// (extrapolated beyond them), sd exact at every point; tensor Gauss in the two reference axes
// least aligned with sd's change over the cell (graded too where the cell's centre line along
// one crosses sd = 0: the source's edges and corners), and along the most aligned one, per
// tangential point, panels graded geometrically towards where sd crosses 0 on that line.
// What limits the accuracy is f's interpolation where the surface crosses a cell (measured in
// docs/formulation.md §2.8); refine_crossed splits those cells.

#include <Eigen/Core>
#include <vector>

#include "softhd/triangle_surface.hpp"

namespace softhd::detail {

class BodyIntegral;
struct BodyIntegralOptions;
class SurfaceDistance;

/// A body meshed by trilinear hexahedra (plain data; the FE is not needed). The cells' corners in
/// Gmsh's order: reference coordinates 0 (−,−,−), 1 (+,−,−), 2 (+,+,−), 3 (−,+,−), 4 (−,−,+),
/// 5 (+,−,+), 6 (+,+,+), 7 (−,+,+); positive Jacobians.
struct HexCells {
  Eigen::MatrixXd nodes;                        ///< N by 3 (current configuration)
  Eigen::Matrix<int, Eigen::Dynamic, 8> cells;  ///< C by 8 node ids
};

/// The box lo + [0, size] meshed by n[0] · n[1] · n[2] hexahedra (tests and measurements).
HexCells hex_box(const Eigen::Vector3d& lo, const Eigen::Vector3d& size, const Eigen::Vector3i& n);
/// The cube [lo, lo + side]³ meshed by n³ hexahedra.
HexCells hex_cube(const Eigen::Vector3d& lo, double side, int n);

/// The outer rule's parameters (defaults: the study's, docs/formulation.md §2.8).
struct CellDistanceOptions {
  double epsilon = 1e-3;      ///< ε > 0 of the kernel (r + ε)^−4
  int tangential_points = 4;  ///< Gauss points per tangential axis of a near cell (1 to 64)
  double first_panel = 0.2;   ///< the graded rule's first panel, × ε (physical length; > 0)
  double grading = 4.0;       ///< the panels' ratio (> 1)
  int panel_points = 3;       ///< Gauss points per panel, and along a line without a crossing
  /// A cell is near (the graded rule) when sd changes sign over its centre and corners, or
  /// the smallest |sd| among them is ≤ near_factor × the cell's extent along ∇sd there (≥ 0);
  /// the others take the 2×2×2 Gauss rule with J itself.
  double near_factor = 0.5;
  /// Near cells: grade the two tangential axes too where the cell's centre line along one
  /// crosses sd = 0 within half a cell (an edge or corner of the source in the cell); false:
  /// tangential_points Gauss points on them always.
  bool grade_tangential = true;
  double tangential_first_panel = 1.0;  ///< their first panel, × ε (> 0)
  int tangential_panel_points = 3;      ///< their Gauss points per panel (1 to 64)
  /// Diagnostics: J by BodyIntegral at every quadrature point of the near cells instead of the
  /// interpolated factor (slow; isolates the interpolation's error from the rule's).
  bool exact_near = false;
  /// Near cells: J = P_ε(sd) + g (g = J − P_ε(sd) interpolated from the samples) where |g| ≤
  /// P_ε(sd)/2, the factor elsewhere; false: the factor everywhere.
  bool hybrid = false;
  /// Diagnostics (value only): J at the cells' corners, each distinct point once, instead of
  /// at every cell's 2×2×2 Gauss points; the factor f = log(J/P_ε(sd)) trilinear through the
  /// corners, and far cells' J = P_ε(sd) exp(f) at their Gauss points (about 1/8 of the J
  /// evaluations on a structured mesh; measures what shared samples cost in accuracy).
  bool node_samples = false;
  /// A far cell farther from the source's surface — sd of one sign at its centre and corners,
  /// the smallest |sd| among them ≥ corner_factor × the cell's extent along ∇sd there — takes
  /// the corner rule instead of the 2×2×2 Gauss rule: J at its corners (the mesh's nodes,
  /// shared with its neighbours) and its centre, weights det J/3 and 16 det J(0)/3, of degree
  /// 3 like the Gauss rule (about 2 evaluations of J per cell instead of 8; its error measured
  /// in docs/formulation.md §2.8). 0: never. ≥ 0; ignored with node_samples and by the
  /// children of refine_crossed.
  double corner_factor = 1.0;
  /// Near cells whose corners and samples lie on both sides of the surface are split into 8
  /// children with samples of their own, this many times (0 to 4).
  int refine_crossed = 0;
  /// J's tree tolerance τ ∈ [0, 1) (BodyIntegralOptions::tolerance: |ΔJ| ≤ τ J at every
  /// sample); 0 (default): all pairs.
  double tolerance = 0.0;
  /// J's near_ratio and angle_points (BodyIntegralOptions: the far rules' and the polar rule's
  /// accuracy, measured in docs/formulation.md §2.8; 4 and 12 keep both below ~1e-9).
  double j_near_ratio = 4.0;
  int j_angle_points = 12;
  int threads = 0;  ///< OpenMP threads (0: softhd's default)
  /// Throws InvalidArgument naming the first invalid field.
  void validate() const;
};

/// The faces of a hexahedral mesh that belong to one cell only, as outward triangles (two per
/// quadrilateral face), over the nodes they use; with point_node, the node of each surface point.
/// InvalidArgument for a node id out of range.
TriangleSurface hex_boundary(const HexCells& body, std::vector<int>* point_node = nullptr);

/// The volume a closed outward triangle surface bounds: Σ_t a·(b × c)/6.
double enclosed_volume(const TriangleSurface& surface);
/// Its gradient with respect to the surface's points (N by 3): Σ_t over the triangles at a point,
/// (b × c)/6 for a, (c × a)/6 for b, (a × b)/6 for c.
Eigen::MatrixXd enclosed_volume_gradient(const TriangleSurface& surface);

/// The directed mean and what it cost.
struct OuterMean {
  double mean = 0.0;      ///< (1/|Ω_Y|) ∫_Ω_Y d̃_X^4
  double volume = 0.0;    ///< |Ω_Y| (the 2×2×2 rule, exact for trilinear cells)
  long near_cells = 0;    ///< cells integrated by the graded rule
  long near_points = 0;   ///< their quadrature points (one signed distance each)
  long corner_cells = 0;  ///< far cells integrated by the corner rule (corner_factor)
};

/// The directed mean's gradient with respect to what it depends on.
struct OuterMeanGradient {
  Eigen::MatrixXd outer;       ///< ∂mean/∂(the outer body's nodes), N_outer by 3
  Eigen::MatrixXd source;      ///< ∂mean/∂(the source's surface points) through J and sd
  double source_volume = 0.0;  ///< ∂mean/∂|Ω_X|
};

/// A^4 of the outer cells against the source (its J, its signed distance, |Ω_X|); with grad,
/// also its gradient (InvalidArgument naming the field for exact_near, hybrid or
/// refine_crossed > 0: the gradient is built for the default rule only).
OuterMean directed_outer_mean(const HexCells& outer, const BodyIntegral& source_j,
                              const SurfaceDistance& source_sd, double source_volume,
                              const CellDistanceOptions& options,
                              OuterMeanGradient* grad = nullptr);

/// A^4 = (1/W) Σ_j w_j d̃_X(y_j)^4 of weighted points (a scan's surface by its surface weights,
/// W = Σ_j w_j > 0) against a source body's J and |Ω_X| (surface_mean.cpp); with grad, its source
/// bars through J and |Ω_X| (grad->outer empty: the points are fixed). OuterMean::volume is W.
/// InvalidArgument for points that are not M by 3 with M weights, M = 0, or W ≤ 0.
OuterMean directed_point_mean(const Eigen::MatrixXd& points, const Eigen::VectorXd& weights,
                              const BodyIntegral& source_j, double source_volume, double epsilon,
                              OuterMeanGradient* grad = nullptr);

/// ρ̃ of two hexahedral bodies (α = β = 4, γ = 2), and its two directed means.
struct CellRho {
  double rho = 0.0;
  OuterMean a;  ///< over Y's cells, against X
  OuterMean b;  ///< over X's cells, against Y
};
/// The gradient of ρ̃ with respect to the nodes of both bodies.
struct CellRhoGradient {
  Eigen::MatrixXd x;  ///< ∂ρ̃/∂(X's nodes), N_x by 3
  Eigen::MatrixXd y;  ///< ∂ρ̃/∂(Y's nodes), N_y by 3
};
/// With grad, also ∂ρ̃/∂ of both bodies' nodes: exact for the discrete ρ̃ (the panels' count fixed,
/// their breakpoints moving with the crossings) where the rule's discrete choices (near or far,
/// the graded axis, which lines cross) do not change; nothing of it is computed without grad.
CellRho cell_rho(const HexCells& x, const HexCells& y, const CellDistanceOptions& options,
                 CellRhoGradient* grad = nullptr);

/// ρ̃ = ((A² + B²)/2)^(1/2) from r's directed means A^4 and B^4 into r->rho (returned), and
/// with ca, cb non-null ∂ρ̃/∂A^4 = 1/(8 ρ̃ √(A^4)) and ∂ρ̃/∂B^4.
double combine_means(CellRho* r, double* ca = nullptr, double* cb = nullptr);

/// Adds scale × a directed mean's bars on its source's surface points (through J, sd and
/// |Ω_X|) to the source's nodes (point_node: hex_boundary's surface point → node map).
void add_source_bars(const OuterMeanGradient& g, double scale, const TriangleSurface& surface,
                     const std::vector<int>& point_node, Eigen::MatrixXd* nodes);

/// The inner integral's options the cell distance uses: ε, α = 4, threads, and J's tolerance,
/// near ratio and angle points.
BodyIntegralOptions body_integral_options(const CellDistanceOptions& options);

/// The half-space profile J of (r + ε)^−4 at signed distance sd (negative inside, depth
/// d = −sd): 4π/(3ε) − π/(d + ε) + πε/(3(d + ε)²) inside, π/(D + ε) − πε/(3(D + ε)²) outside.
double halfspace_profile(double sd, double epsilon);

}  // namespace softhd::detail

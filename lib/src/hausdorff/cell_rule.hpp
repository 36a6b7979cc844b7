#pragma once
// The pieces of the outer cells' rule (docs/formulation.md §2.8, "The outer mean in C++"),
// internal to cell_distance.cpp (the value) and cell_distance_gradient.cpp (its gradient): both
// compose these, so the gradient differentiates the very rule the value uses. The trilinear map,
// the integrand d̃^4, the factor's interpolation, the lines of a near cell (their ends, where sd
// crosses 0 on them, their graded points) and the samples.

#include <cmath>
#include <vector>

#include "../common/surface_bvh.hpp"
#include "cell_distance.hpp"

namespace softhd::detail {

class BodyIntegral;

namespace cell_rule {

// The corners' reference signs (Gmsh's order).
constexpr int kSign[8][3] = {{-1, -1, -1}, {1, -1, -1}, {1, 1, -1}, {-1, 1, -1},
                             {-1, -1, 1},  {1, -1, 1},  {1, 1, 1},  {-1, 1, 1}};

// One cell's corners (8 by 3, row-major).
struct Cell {
  double p[8][3];
};

// x(ξ) = Σ_i N_i(ξ) x_i, N_i = Π_k (1 + ξ_k s_ik)/2, and det ∂x/∂ξ.
inline void map_point(const Cell& c, const double xi[3], double x[3], double* det) {
  double jac[3][3] = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}};  // jac[k][d] = ∂x_d/∂ξ_k
  x[0] = x[1] = x[2] = 0.0;
  for (int i = 0; i < 8; ++i) {
    double f[3], df[3];
    for (int k = 0; k < 3; ++k) {
      f[k] = 0.5 * (1.0 + xi[k] * kSign[i][k]);
      df[k] = 0.5 * kSign[i][k];
    }
    const double n = f[0] * f[1] * f[2];
    const double dn[3] = {df[0] * f[1] * f[2], f[0] * df[1] * f[2], f[0] * f[1] * df[2]};
    for (int d = 0; d < 3; ++d) {
      x[d] += n * c.p[i][d];
      for (int k = 0; k < 3; ++k) jac[k][d] += dn[k] * c.p[i][d];
    }
  }
  if (det)
    *det = jac[0][0] * (jac[1][1] * jac[2][2] - jac[1][2] * jac[2][1]) -
           jac[0][1] * (jac[1][0] * jac[2][2] - jac[1][2] * jac[2][0]) +
           jac[0][2] * (jac[1][0] * jac[2][1] - jac[1][1] * jac[2][0]);
}

inline SignedDistance sd_at(const SurfaceDistance& s, const double x[3]) {
  return s.at(Eigen::Vector3d(x[0], x[1], x[2]));
}

inline double signed_distance(const SurfaceDistance& s, const double x[3]) {
  return sd_at(s, x).sd;
}

// The same from a line's candidates (line_candidates): the same values, bit for bit.
inline SignedDistance sd_at(const SurfaceDistance& s, const double x[3],
                            const SurfaceDistance::Candidates& k) {
  return s.at(Eigen::Vector3d(x[0], x[1], x[2]), k);
}

// d̃^4 = ((J/|Ω_X|)^(−1/4) − ε)^4.
inline double field4(double j, double source_volume, double eps) {
  const double d = std::pow(j / source_volume, -0.25) - eps;
  const double d2 = d * d;
  return d2 * d2;
}

// The trilinear weights through the samples at ξ_k = ±1/√3 (sample g = i + 2j + 4k):
// t_k = (√3 ξ_k + 1)/2, w_g = Π_k (t_k or 1 − t_k).
inline void sample_weights(const double xi[3], double w[8]) {
  const double r3 = std::sqrt(3.0);
  double t[3];
  for (int k = 0; k < 3; ++k) t[k] = 0.5 * (xi[k] * r3 + 1.0);
  for (int g = 0; g < 8; ++g) {
    double wgt = 1.0;
    for (int k = 0; k < 3; ++k) wgt *= ((g >> k) & 1) ? t[k] : 1.0 - t[k];
    w[g] = wgt;
  }
}

// f(ξ) = Σ_g w_g(ξ) f_g, trilinear through the samples.
inline double interpolate(const double f[8], const double xi[3]) {
  double w[8];
  sample_weights(xi, w);
  double v = 0.0;
  for (int g = 0; g < 8; ++g) v += w[g] * f[g];
  return v;
}

// The rule's fixed parts.
struct Rule {
  std::vector<double> tx, tw;  // tangential Gauss
  std::vector<double> px, pw;  // per panel, and along a line without a crossing
  double eps, d0, q, volume;   // ε, first panel (physical), ratio, |Ω_X|
  bool grade_tangential;
  double d0t;                           // the tangential rule's first panel (physical)
  std::vector<double> qx, qw;           // its points per panel
  const BodyIntegral* exact = nullptr;  // diagnostics: J itself at every near point
  bool hybrid = false;
};
Rule make_rule(const CellDistanceOptions& o, double source_volume);

// A line's rule on [−1, 1]: points x, weights w. Graded (about the crossing f with first panel
// d0, both in reference units), and asked for, also the rates ∂x/∂f, ∂x/∂d0, ∂w/∂f, ∂w/∂d0
// (the breakpoints f ± d0 q^k move with f and d0; ±1 stay).
struct LineRule {
  std::vector<double> x, w;
  bool graded = false;
  double d0 = 0.0;
  std::vector<double> x_f, x_d, w_f, w_d;
};

// Composite Gauss (gx, gw per panel) on [−1, 1], panels graded geometrically (first d0, ratio
// q) on both sides of f (inside or outside the interval).
void graded_line(double f, double d0, double q, const std::vector<double>& gx,
                 const std::vector<double>& gw, LineRule* out, bool rates);

// Where sd crosses 0 on a reference line: t (a value beyond ±2: none within half a cell).
enum class RootKind { kNone, kInside, kExtrapolated };
struct Root {
  double t = 1e300;
  RootKind kind = RootKind::kNone;
};

// The crossing on the line ξ_axis ∈ [−1, 1] (the other two coordinates in xi), s0 and s1 sd at
// its ends: Illinois regula falsi inside, the ends' linear extrapolation outside.
Root crossing(const Cell& c, const SurfaceDistance& s, double xi[3], int axis, double s0,
              double s1);

// A line of a cell along reference axis `axis` through xi: sd at its ends, its physical
// length, its crossing and its rule.
struct Line {
  SignedDistance s0, s1;
  double length = 0.0;
  Root root;
  LineRule rule;
};

// The line's ends (ξ_axis = ∓1): sd there and the length between them.
void line_ends(const Cell& c, const SurfaceDistance& s, const double xi[3], int axis, Line* line);

// The candidates for the closest triangles of the line's points (its ends known): the ball
// about its middle m of radius max(|s0|, |s1|) + L. A point y of the line a from an end has
// |sd(y)| ≤ |s_end| + a, so |sd(y)| ≤ max(|s0|, |s1|) + L/2 ≤ radius − |y − m|, the test of
// SurfaceDistance::at(y, candidates) (which falls back on the full search where it fails).
SurfaceDistance::Candidates line_candidates(const Cell& c, const SurfaceDistance& s,
                                            const double xi[3], int axis, const Line& line);

// The line's rule, its ends known: graded (first panel d0 physical, gx/gw per panel, ratio q)
// towards the crossing when it lies within half a cell, else the plain points (fx, fw).
void line_rule(const Cell& c, const SurfaceDistance& s, const double xi[3], int axis, double d0,
               double q, const std::vector<double>& gx, const std::vector<double>& gw,
               const std::vector<double>& fx, const std::vector<double>& fw, Line* line,
               bool rates);

// The cell's centre lines (ends only) and the axis along which sd changes most between
// opposite face centres (ties: the first).
int cell_axes(const Cell& c, const SurfaceDistance& s, Line centre[3]);

// The tangential rule along axis k (the centre line's ends known): graded towards its crossing
// when rule.grade_tangential, else Gauss.
void tangential_rule(const Cell& c, const SurfaceDistance& s, const Rule& rule, int k, Line* centre,
                     bool rates);

// A cell's corners from the mesh.
Cell cell_of(const HexCells& body, Eigen::Index c);

// Every cell's 2×2×2 Gauss points (rows 8c + q, q = i + 2j + 4k) and their weights det J.
void cell_samples(const std::vector<Cell>& cells, Eigen::MatrixXd* samples,
                  Eigen::VectorXd* weight);

// The reference point of sample q.
void sample_xi(int q, double xi[3]);

// Whether the graded rule takes the cell: sd changes sign over its centre and corners, or the
// smallest |sd| among them is ≤ near_factor × the cell's extent along ∇sd at that point.
bool is_near(const Cell& c, const SurfaceDistance& s, double near_factor);

// The outer rule a cell takes: the graded rule (near), the 2×2×2 rule with J at its Gauss
// points (far), or, farther from the surface (sd of one sign at its centre and corners, the
// smallest |sd| among them ≥ corner_factor × the cell's extent along ∇sd there; corner_factor
// ≤ 0: never), the corner rule: J at its corners (the mesh's nodes, shared with its
// neighbours) and its centre,
//
//     ∫_cell F dx ≈ Σ_i (1/3) det J(ξ_i) F(x_i) + (16/3) det J(0) F(x(0))   (ξ_i = ±1, ±1, ±1),
//
// of degree 3 in ξ like the 2×2×2 Gauss rule (corner_rule_weights).
enum class CellKind { kFar, kNear, kCorner };
CellKind cell_kind(const Cell& c, const SurfaceDistance& s, double near_factor,
                   double corner_factor);
// Every cell's kind (OpenMP over the cells).
std::vector<CellKind> cell_kinds(const std::vector<Cell>& cells, const SurfaceDistance& s,
                                 double near_factor, double corner_factor, int threads);
// The corner rule's weights: w[i] = det J(ξ_i)/3 at corner i, w[8] = 16 det J(0)/3.
void corner_rule_weights(const Cell& c, double w[9]);

// The points J is evaluated at: the nodes the corner cells use (rows node_row[v], −1 for the
// others), then per cell its 2×2×2 Gauss points (rows first[c] + q, q = i + 2j + 4k), or its
// centre alone (row first[c]) for a corner cell.
struct JPoints {
  Eigen::MatrixXd points;
  std::vector<Eigen::Index> first, node_row;
};
// body: the cells' mesh (its node ids), or null when no cell is a corner cell.
JPoints j_points(const std::vector<Cell>& cells, const std::vector<CellKind>& kind,
                 const Eigen::MatrixXd& samples, const HexCells* body);

// The half-space profile's slope dP_ε/dsd (continuous at sd = 0: −π/(3ε²)).
double halfspace_slope(double sd, double epsilon);

}  // namespace cell_rule

/// The directed mean with its gradient (default rule only; cell_distance_gradient.cpp).
OuterMean outer_mean_with_gradient(const HexCells& outer, const BodyIntegral& source_j,
                                   const SurfaceDistance& source_sd, double source_volume,
                                   const CellDistanceOptions& options, OuterMeanGradient* grad);

}  // namespace softhd::detail

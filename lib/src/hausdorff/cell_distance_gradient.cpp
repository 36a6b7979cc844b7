// The directed outer mean with its exact gradient (cell_distance.hpp; docs/formulation.md §2.8,
// "Gradients"): a reverse pass through the rule of cell_rule.hpp, one function per formula.
// S = Σ_cells ∫ d̃^4 and |Ω_Y| = Σ_cells Σ_q det J_q are differentiated with respect to the outer
// cells' corners, the source's surface points (through J and sd) and |Ω_X|; mean = S/|Ω_Y|.
// The graded panels keep their count and move with the crossing t* of each line:
// sd(y(t*)) = 0 ⇒ δt* = −δsd/(∂sd/∂t).

#include <Eigen/Core>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "../common/surface_bvh.hpp"
#include "body_integral.hpp"
#include "cell_distance.hpp"
#include "cell_rule.hpp"
#include "softhd/error.hpp"
#include "softhd/parallel.hpp"

namespace softhd::detail {
namespace {

using namespace cell_rule;  // NOLINT: the rule's pieces

using SparseBars = std::vector<std::pair<int, Eigen::Vector3d>>;

// Bars on the source's surface points from one cell: a dense buffer (one per thread) and the
// points touched, handed over per cell as a sparse list (merged in cell order: deterministic).
class SourceBar {
 public:
  explicit SourceBar(Eigen::Index points)
      : dense_(3 * static_cast<std::size_t>(points), 0.0),
        seen_(static_cast<std::size_t>(points), 0) {}
  void add(int a, const Eigen::Vector3d& v, double scale) {
    if (!seen_[a]) seen_[a] = 1, touched_.push_back(a);
    for (int d = 0; d < 3; ++d) dense_[3 * a + d] += scale * v[d];
  }
  // Moves the bars into out, clearing the buffer.
  void take(SparseBars* out) {
    out->clear();
    for (int a : touched_) {
      out->emplace_back(a, Eigen::Vector3d(dense_[3 * a], dense_[3 * a + 1], dense_[3 * a + 2]));
      dense_[3 * a] = dense_[3 * a + 1] = dense_[3 * a + 2] = 0.0;
      seen_[a] = 0;
    }
    touched_.clear();
  }

 private:
  std::vector<double> dense_;
  std::vector<char> seen_;
  std::vector<int> touched_;
};

// What a near cell's reverse pass accumulates.
struct CellBar {
  double p[8][3] = {};  // ∂/∂ its corners
  double f[8] = {};     // ∂/∂ f_s (the samples' log factors)
  double volume = 0.0;  // ∂/∂|Ω_X|
  SourceBar* source;    // ∂/∂ the source's surface points
};

// ∂x/∂ξ_axis at ξ: Σ_i ∂N_i/∂ξ_axis x_i.
void axis_tangent(const Cell& c, const double xi[3], int axis, double t[3]) {
  t[0] = t[1] = t[2] = 0.0;
  for (int i = 0; i < 8; ++i) {
    double dn = 0.5 * kSign[i][axis];
    for (int k = 0; k < 3; ++k)
      if (k != axis) dn *= 0.5 * (1.0 + xi[k] * kSign[i][k]);
    for (int d = 0; d < 3; ++d) t[d] += dn * c.p[i][d];
  }
}

// The adjoint of x(ξ) = Σ_i N_i x_i and det J (J_kd = ∂x_d/∂ξ_k, cof = ∂det/∂J) at ξ:
// x̄_i += N_i x̄ + det̄ Σ_k cof_k ∂_k N_i;  ξ̄_m += J_m·x̄ + det̄ Σ_{k≠m} Σ_i ∂_k∂_m N_i (cof_k·x_i)
// (the trilinear N_i's only second derivatives are the mixed ones). xibar may be null.
void map_adjoint(const Cell& c, const double xi[3], const double xbar[3], double detbar,
                 double pbar[8][3], double* xibar) {
  double f[8][3], df[8][3], n[8], dn[8][3], jac[3][3] = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}};
  for (int i = 0; i < 8; ++i) {
    for (int k = 0; k < 3; ++k) {
      f[i][k] = 0.5 * (1.0 + xi[k] * kSign[i][k]);
      df[i][k] = 0.5 * kSign[i][k];
    }
    n[i] = f[i][0] * f[i][1] * f[i][2];
    dn[i][0] = df[i][0] * f[i][1] * f[i][2];
    dn[i][1] = f[i][0] * df[i][1] * f[i][2];
    dn[i][2] = f[i][0] * f[i][1] * df[i][2];
    for (int k = 0; k < 3; ++k)
      for (int d = 0; d < 3; ++d) jac[k][d] += dn[i][k] * c.p[i][d];
  }
  double cof[3][3];
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b)
      cof[a][b] = jac[(a + 1) % 3][(b + 1) % 3] * jac[(a + 2) % 3][(b + 2) % 3] -
                  jac[(a + 1) % 3][(b + 2) % 3] * jac[(a + 2) % 3][(b + 1) % 3];
  for (int i = 0; i < 8; ++i)
    for (int d = 0; d < 3; ++d)
      pbar[i][d] += n[i] * xbar[d] +
                    detbar * (cof[0][d] * dn[i][0] + cof[1][d] * dn[i][1] + cof[2][d] * dn[i][2]);
  if (!xibar) return;
  for (int m = 0; m < 3; ++m)
    xibar[m] += jac[m][0] * xbar[0] + jac[m][1] * xbar[1] + jac[m][2] * xbar[2];
  if (detbar == 0.0) return;
  for (int i = 0; i < 8; ++i) {
    double cp[3];  // cof_k·x_i
    for (int k = 0; k < 3; ++k)
      cp[k] = cof[k][0] * c.p[i][0] + cof[k][1] * c.p[i][1] + cof[k][2] * c.p[i][2];
    for (int m = 0; m < 3; ++m)
      for (int k = 0; k < 3; ++k)
        if (k != m) xibar[m] += detbar * df[i][k] * df[i][m] * f[i][3 - k - m] * cp[k];
  }
}

// The adjoint of sd(y) (surface_bvh.hpp): ∂sd/∂y = n̂, ∂sd/∂x_a = −λ_a n̂ for the corners a of
// the closest triangle; w the bar of sd.
void sd_adjoint(const SurfaceDistance& s, const SignedDistance& q, double w, double ybar[3],
                SourceBar* source) {
  for (int d = 0; d < 3; ++d) ybar[d] += w * q.gradient[d];
  for (int a = 0; a < 3; ++a)
    if (q.closest.where.lambda[a] != 0.0)
      source->add(s.surface().triangles(q.closest.triangle, a), q.gradient,
                  -w * q.closest.where.lambda[a]);
}

// φ(ξ) = Σ_g w_g(ξ) f_g: f̄_g += φ̄ w_g, ξ̄_k += φ̄ Σ_g f_g ∂w_g/∂ξ_k (∂t_k/∂ξ_k = √3/2).
void interpolate_adjoint(const double f[8], const double xi[3], double phibar, double fbar[8],
                         double xibar[3]) {
  const double r3 = std::sqrt(3.0);
  double t[3], w[8];
  for (int k = 0; k < 3; ++k) t[k] = 0.5 * (xi[k] * r3 + 1.0);
  sample_weights(xi, w);
  for (int g = 0; g < 8; ++g) {
    fbar[g] += phibar * w[g];
    for (int k = 0; k < 3; ++k) {
      double dw = ((g >> k) & 1) ? 0.5 * r3 : -0.5 * r3;
      for (int l = 0; l < 3; ++l)
        if (l != k) dw *= ((g >> l) & 1) ? t[l] : 1.0 - t[l];
      xibar[k] += phibar * f[g] * dw;
    }
  }
}

// F = d^4, d = (J/V)^(−1/4) − ε: ∂F/∂J = −d³ (J/V)^(−1/4)/J, ∂F/∂V = d³ (J/V)^(−1/4)/V.
struct Field4 {
  double f, dj, dv;
};
Field4 field4_rates(double j, double v, double eps) {
  const double u = std::pow(j / v, -0.25), d = u - eps, d2 = d * d;
  return {d2 * d2, -d2 * d * u / j, d2 * d * u / v};
}

// sd at the end ξ_axis = end of a line, bar w: into the corners, the line's other two
// coordinates (xibar) and the source.
void end_adjoint(const Cell& c, const SurfaceDistance& s, const double xi_line[3], int axis,
                 double end, const SignedDistance& q, double w, CellBar* bar, double xibar[3]) {
  double xi[3] = {xi_line[0], xi_line[1], xi_line[2]}, ybar[3] = {0, 0, 0}, xb[3] = {0, 0, 0};
  xi[axis] = end;
  sd_adjoint(s, q, w, ybar, bar->source);
  map_adjoint(c, xi, ybar, 0.0, bar->p, xb);
  for (int k = 0; k < 3; ++k)
    if (k != axis) xibar[k] += xb[k];
}

// Below this |∂sd/∂t| relative to the line's length the line lies in the source's surface
// (within rounding: coincident or grid-aligned faces), its crossing is arbitrary and its rate
// unbounded: it is held fixed there.
constexpr double kFlat = 1e-12;

// The crossing t's adjoint (bar tbar). Inside: sd(y(ξ_line, t)) = 0 ⇒ δt = −δsd/(n̂·∂y/∂ξ_axis),
// δsd at fixed t (the corners, the other coordinates, the source). Extrapolated:
// t = −1 + 2 s0/(s0 − s1) ⇒ ∂t/∂s0 = −2 s1/(s0 − s1)², ∂t/∂s1 = 2 s0/(s0 − s1)².
void root_adjoint(const Cell& c, const SurfaceDistance& s, const double xi_line[3], int axis,
                  const Line& line, double tbar, CellBar* bar, double xibar[3]) {
  if (tbar == 0.0) return;
  if (line.root.kind == RootKind::kExtrapolated) {
    const double s0 = line.s0.sd, s1 = line.s1.sd, den = (s0 - s1) * (s0 - s1);
    if (std::abs(s0 - s1) <= kFlat * line.length) return;
    end_adjoint(c, s, xi_line, axis, -1.0, line.s0, tbar * (-2.0 * s1 / den), bar, xibar);
    end_adjoint(c, s, xi_line, axis, 1.0, line.s1, tbar * (2.0 * s0 / den), bar, xibar);
    return;
  }
  if (line.root.kind != RootKind::kInside) return;
  double xi[3] = {xi_line[0], xi_line[1], xi_line[2]}, y[3], tangent[3];
  xi[axis] = line.root.t;
  map_point(c, xi, y, nullptr);
  const SignedDistance q = sd_at(s, y);
  axis_tangent(c, xi, axis, tangent);
  const double slope =
      q.gradient[0] * tangent[0] + q.gradient[1] * tangent[1] + q.gradient[2] * tangent[2];
  if (std::abs(slope) <= kFlat * line.length) return;
  end_adjoint(c, s, xi_line, axis, line.root.t, q, -tbar / slope, bar, xibar);
}

// L = |x(ξ_axis = 1) − x(ξ_axis = −1)|: x̄(1) = L̄ (x(1) − x(−1))/L = −x̄(−1).
void length_adjoint(const Cell& c, const double xi_line[3], int axis, double length, double lbar,
                    CellBar* bar, double xibar[3]) {
  if (lbar == 0.0) return;
  double xi[3] = {xi_line[0], xi_line[1], xi_line[2]}, x0[3], x1[3], xb[3] = {0, 0, 0};
  xi[axis] = -1.0;
  map_point(c, xi, x0, nullptr);
  xi[axis] = 1.0;
  map_point(c, xi, x1, nullptr);
  double u1[3], u0[3];
  for (int d = 0; d < 3; ++d) u1[d] = lbar * (x1[d] - x0[d]) / length, u0[d] = -u1[d];
  map_adjoint(c, xi, u1, 0.0, bar->p, xb);
  xi[axis] = -1.0;
  map_adjoint(c, xi, u0, 0.0, bar->p, xb);
  for (int k = 0; k < 3; ++k)
    if (k != axis) xibar[k] += xb[k];
}

// A graded line's rule from its points' bars: t̄ = Σ_k (x̄_k ∂x_k/∂t + w̄_k ∂w_k/∂t), d̄0 likewise
// with ∂/∂d0; d0 = 2 d0_phys/L ⇒ L̄ = −d̄0 d0/L.
void line_adjoint(const Cell& c, const SurfaceDistance& s, const double xi_line[3], int axis,
                  const Line& line, const std::vector<double>& xbar,
                  const std::vector<double>& wbar, CellBar* bar, double xibar[3]) {
  const LineRule& r = line.rule;
  if (!r.graded) return;
  double tbar = 0.0, dbar = 0.0;
  for (std::size_t k = 0; k < r.x.size(); ++k) {
    tbar += xbar[k] * r.x_f[k] + wbar[k] * r.w_f[k];
    dbar += xbar[k] * r.x_d[k] + wbar[k] * r.w_d[k];
  }
  root_adjoint(c, s, xi_line, axis, line, tbar, bar, xibar);
  length_adjoint(c, xi_line, axis, line.length, -dbar * r.d0 / line.length, bar, xibar);
}

// One point ξ of a near cell, weight W (the tensor rule's): term = W det F(J), J = P_ε(sd(y))
// exp(φ(ξ)), y = x(ξ). Returns the term; adds the bars of the corners, f_s, |Ω_X| and the
// source to bar, and ∂term/∂W, ∂term/∂ξ to *wbar, xibar.
double point_adjoint(const Cell& c, const double f[8], const SurfaceDistance& s,
                     const SurfaceDistance::Candidates& near, const Rule& r, const double xi[3],
                     double weight, CellBar* bar, double* wbar, double xibar[3]) {
  double y[3], det;
  map_point(c, xi, y, &det);
  const SignedDistance q = sd_at(s, y, near);
  const double p = halfspace_profile(q.sd, r.eps), e = std::exp(interpolate(f, xi)), j = p * e;
  const Field4 F = field4_rates(j, r.volume, r.eps);
  const double term = weight * det * F.f;
  *wbar = det * F.f;
  const double jbar = weight * det * F.dj;  // J̄; then P̄ = J̄ e^φ, φ̄ = J̄ J
  bar->volume += weight * det * F.dv;
  double ybar[3] = {0, 0, 0};
  sd_adjoint(s, q, jbar * e * halfspace_slope(q.sd, r.eps), ybar, bar->source);
  interpolate_adjoint(f, xi, jbar * j, bar->f, xibar);
  map_adjoint(c, xi, ybar, weight * F.f, bar->p, xibar);
  return term;
}

// ∫_cell d̃^4 by the graded rule (the value's near_cell, cell_distance.cpp) and its reverse pass:
// per line its points, then the line's rule; then the two tangential rules.
double near_cell_adjoint(const Cell& c, const double f[8], const SurfaceDistance& s, const Rule& r,
                         CellBar* bar, long* points) {
  Line centre[3];
  const int axis = cell_axes(c, s, centre);
  const int b = (axis + 1) % 3, e = (axis + 2) % 3;
  tangential_rule(c, s, r, b, &centre[b], true);
  tangential_rule(c, s, r, e, &centre[e], true);
  const LineRule &tb = centre[b].rule, &te = centre[e].rule;
  std::vector<double> bxbar(tb.x.size(), 0.0), bwbar(tb.x.size(), 0.0);
  std::vector<double> exbar(te.x.size(), 0.0), ewbar(te.x.size(), 0.0), lxbar, lwbar;
  double sum = 0.0;
  Line line;
  for (std::size_t i = 0; i < tb.x.size(); ++i)
    for (std::size_t j = 0; j < te.x.size(); ++j) {
      double xi[3], xib[3] = {0, 0, 0};
      xi[b] = tb.x[i], xi[e] = te.x[j], xi[axis] = 0.0;
      line_ends(c, s, xi, axis, &line);
      line_rule(c, s, xi, axis, r.d0, r.q, r.px, r.pw, r.px, r.pw, &line, true);
      const std::vector<double>&lx = line.rule.x, &lw = line.rule.w;
      lxbar.assign(lx.size(), 0.0);
      lwbar.assign(lx.size(), 0.0);
      const SurfaceDistance::Candidates near = line_candidates(c, s, xi, axis, line);
      for (std::size_t k = 0; k < lx.size(); ++k) {
        xi[axis] = lx[k];
        double wbar, pxi[3] = {0, 0, 0};
        sum += point_adjoint(c, f, s, near, r, xi, tb.w[i] * te.w[j] * lw[k], bar, &wbar, pxi);
        bwbar[i] += wbar * te.w[j] * lw[k];  // W = w_b w_e w_l
        ewbar[j] += wbar * tb.w[i] * lw[k];
        lwbar[k] += wbar * tb.w[i] * te.w[j];
        xib[b] += pxi[b], xib[e] += pxi[e], lxbar[k] += pxi[axis];
      }
      xi[axis] = 0.0;
      line_adjoint(c, s, xi, axis, line, lxbar, lwbar, bar, xib);
      bxbar[i] += xib[b], exbar[j] += xib[e];
      *points += static_cast<long>(lx.size());
    }
  const double zero[3] = {0.0, 0.0, 0.0};
  double unused[3] = {0.0, 0.0, 0.0};  // the centre lines' coordinates are fixed
  line_adjoint(c, s, zero, b, centre[b], bxbar, bwbar, bar, unused);
  line_adjoint(c, s, zero, e, centre[e], exbar, ewbar, bar, unused);
  return sum;
}

// One outer cell's part of S and its bars: the corners' (the near rule's; the samples' are
// added later from jbar, sdbar, detbar), the samples' J, sd and det J, |Ω_X|'s, the source's.
struct CellPart {
  double value = 0.0, volume = 0.0;
  bool near = false, corner = false;
  long points = 0;
  double p[8][3] = {};
  double jbar[8] = {}, sdbar[8] = {}, detbar[8] = {};  // a corner cell's: at its corners
  double jbar_centre = 0.0, detbar_centre = 0.0;       // a corner cell's centre
  SparseBars source;
};

// A far cell: Σ_q det J_q F(J_q) (the 2×2×2 rule).
void far_part(const double* det, const double* j_s, double volume, double eps, CellPart* out) {
  for (int q = 0; q < 8; ++q) {
    const Field4 F = field4_rates(j_s[q], volume, eps);
    out->value += det[q] * F.f;
    out->jbar[q] = det[q] * F.dj;
    out->detbar[q] = F.f;
    out->volume += det[q] * F.dv;
  }
}

// A corner cell: S_c = Σ_i w_i F(J_i) + w_c F(J_c), w_i = det J(ξ_i)/3, w_c = 16 det J(0)/3 ⇒
// J̄_i = w_i F′(J_i), det̄(ξ_i) = F(J_i)/3, J̄_c = w_c F′(J_c), det̄(0) = 16 F(J_c)/3.
void corner_part(const Cell& cell, const double j_corner[8], double j_centre, double volume,
                 double eps, CellPart* out) {
  double w[9];
  corner_rule_weights(cell, w);
  out->corner = true;
  for (int i = 0; i < 8; ++i) {
    const Field4 F = field4_rates(j_corner[i], volume, eps);
    out->value += w[i] * F.f;
    out->jbar[i] = w[i] * F.dj;
    out->detbar[i] = F.f / 3.0;
    out->volume += w[i] * F.dv;
  }
  const Field4 F = field4_rates(j_centre, volume, eps);
  out->value += w[8] * F.f;
  out->jbar_centre = w[8] * F.dj;
  out->detbar_centre = 16.0 * F.f / 3.0;
  out->volume += w[8] * F.dv;
}

// A near cell: the graded rule with f_s = log(J_s/P_ε(sd_s)) ⇒ J̄_s = f̄_s/J_s,
// s̄d_s = −f̄_s P_ε′(sd_s)/P_ε(sd_s).
void near_part(const Cell& cell, const double* j_s, const SignedDistance* sd_s,
               const SurfaceDistance& s, const Rule& rule, SourceBar* source, CellPart* out) {
  double f[8];
  for (int q = 0; q < 8; ++q) f[q] = std::log(j_s[q] / halfspace_profile(sd_s[q].sd, rule.eps));
  CellBar bar;
  bar.source = source;
  out->near = true;
  out->value = near_cell_adjoint(cell, f, s, rule, &bar, &out->points);
  for (int q = 0; q < 8; ++q) {
    out->jbar[q] = bar.f[q] / j_s[q];
    out->sdbar[q] =
        -bar.f[q] * halfspace_slope(sd_s[q].sd, rule.eps) / halfspace_profile(sd_s[q].sd, rule.eps);
  }
  for (int i = 0; i < 8; ++i)
    for (int d = 0; d < 3; ++d) out->p[i][d] = bar.p[i][d];
  out->volume = bar.volume;
  source->take(&out->source);
}

// Every cell's part (OpenMP over the cells, each cell's own).
std::vector<CellPart> cell_parts(const std::vector<Cell>& cells, const HexCells& outer,
                                 const std::vector<CellKind>& kind, const JPoints& jp,
                                 const Eigen::VectorXd& weight, const Eigen::VectorXd& j_all,
                                 const std::vector<SignedDistance>& sd_s, const SurfaceDistance& s,
                                 const Rule& rule, const CellDistanceOptions& o) {
  std::vector<CellPart> parts(cells.size());
  const int threads = resolve_threads(o.threads);
#pragma omp parallel num_threads(threads)
  {
    SourceBar source(s.surface().points.rows());
#pragma omp for schedule(dynamic, 4)
    for (std::size_t c = 0; c < cells.size(); ++c) {
      const double* j_s = &j_all[jp.first[c]];
      if (kind[c] == CellKind::kCorner) {
        double j_corner[8];
        for (int i = 0; i < 8; ++i)
          j_corner[i] = j_all[jp.node_row[outer.cells(static_cast<Eigen::Index>(c), i)]];
        corner_part(cells[c], j_corner, j_s[0], rule.volume, o.epsilon, &parts[c]);
      } else if (kind[c] == CellKind::kFar) {
        far_part(&weight[8 * c], j_s, rule.volume, o.epsilon, &parts[c]);
      } else {
        near_part(cells[c], j_s, &sd_s[8 * c], s, rule, &source, &parts[c]);
      }
    }
  }
  return parts;
}

// The samples' bars into the corners, y_s = x(ξ_s): ȳ_s = J̄_s ∂J/∂y + s̄d_s n̂_s, and det J_s's
// (det̄_s into ∂S; 1 into ∂|Ω_Y|); a corner cell's J̄ ∂J/∂y and det̄ at its corners and centre.
// Adds to the outer nodes' ∂S (ds) and ∂|Ω_Y| (dv).
void samples_adjoint(const HexCells& outer, const std::vector<Cell>& cells,
                     const std::vector<CellPart>& parts, const JPoints& jp,
                     const Eigen::MatrixXd& dj, const std::vector<SignedDistance>& sd_s,
                     Eigen::MatrixXd* ds, Eigen::MatrixXd* dv) {
  for (std::size_t c = 0; c < cells.size(); ++c) {
    const CellPart& part = parts[c];
    double ps[8][3], pv[8][3] = {};
    for (int i = 0; i < 8; ++i)
      for (int d = 0; d < 3; ++d) ps[i][d] = part.p[i][d];
    if (part.corner) {
      for (int i = 0; i < 9; ++i) {  // the corners ξ_i, then the centre
        const Eigen::Index row =
            i < 8 ? jp.node_row[outer.cells(static_cast<Eigen::Index>(c), i)] : jp.first[c];
        const double jb = i < 8 ? part.jbar[i] : part.jbar_centre;
        double xi[3] = {0.0, 0.0, 0.0}, ybar[3];
        if (i < 8)
          for (int k = 0; k < 3; ++k) xi[k] = kSign[i][k];
        for (int d = 0; d < 3; ++d) ybar[d] = jb * dj(row, d);
        map_adjoint(cells[c], xi, ybar, i < 8 ? part.detbar[i] : part.detbar_centre, ps, nullptr);
      }
    }
    for (int q = 0; q < 8; ++q) {
      double xi[3];
      sample_xi(q, xi);
      const double none[3] = {0.0, 0.0, 0.0};
      map_adjoint(cells[c], xi, none, 1.0, pv, nullptr);
      if (part.corner) continue;
      double ybar[3];
      const Eigen::Index r = static_cast<Eigen::Index>(8 * c + q);
      for (int d = 0; d < 3; ++d)
        ybar[d] = part.jbar[q] * dj(jp.first[c] + q, d) + part.sdbar[q] * sd_s[r].gradient[d];
      map_adjoint(cells[c], xi, ybar, part.detbar[q], ps, nullptr);
    }
    for (int i = 0; i < 8; ++i) {
      const int node = outer.cells(static_cast<Eigen::Index>(c), i);
      for (int d = 0; d < 3; ++d) (*ds)(node, d) += ps[i][d], (*dv)(node, d) += pv[i][d];
    }
  }
}

void refuse_diagnostics(const CellDistanceOptions& o) {
  auto refuse = [](const char* field) {
    throw InvalidArgument(std::string("cell distance options: the gradient is not built for ") +
                          field);
  };
  if (o.exact_near) refuse("exact_near (must be false)");
  if (o.hybrid) refuse("hybrid (must be false)");
  if (o.refine_crossed != 0) refuse("refine_crossed (must be 0)");
  if (o.node_samples) refuse("node_samples (must be false)");
}

}  // namespace

OuterMean outer_mean_with_gradient(const HexCells& outer, const BodyIntegral& source_j,
                                   const SurfaceDistance& source_sd, double source_volume,
                                   const CellDistanceOptions& options, OuterMeanGradient* grad) {
  refuse_diagnostics(options);
  const Rule rule = make_rule(options, source_volume);
  std::vector<Cell> cells;
  for (Eigen::Index c = 0; c < outer.cells.rows(); ++c) cells.push_back(cell_of(outer, c));
  Eigen::MatrixXd samples, dj;
  Eigen::VectorXd weight, j_all;
  cell_samples(cells, &samples, &weight);
  const int threads = resolve_threads(options.threads);
  const std::vector<CellKind> kind =
      cell_kinds(cells, source_sd, options.near_factor, options.corner_factor, threads);
  const JPoints jp = j_points(cells, kind, samples, &outer);
  source_j.evaluate(jp.points, &j_all, &dj);
  const std::vector<SignedDistance> sd_s = source_sd.at_rows(samples, threads);
  const std::vector<CellPart> parts =
      cell_parts(cells, outer, kind, jp, weight, j_all, sd_s, source_sd, rule, options);
  OuterMean out;
  double sum = 0.0, dvolume = 0.0;  // S, ∂S/∂|Ω_X|
  Eigen::VectorXd jbar = Eigen::VectorXd::Zero(jp.points.rows()), sdbar(samples.rows());
  Eigen::MatrixXd dsource = Eigen::MatrixXd::Zero(source_sd.surface().points.rows(), 3);
  for (std::size_t c = 0; c < parts.size(); ++c) {
    const CellPart& p = parts[c];
    sum += p.value;
    dvolume += p.volume;
    out.near_cells += p.near;
    out.near_points += p.points;
    out.corner_cells += p.corner;
    for (int q = 0; q < 8; ++q) sdbar[8 * c + q] = p.sdbar[q];
    if (p.corner) {  // the corners' rows are shared with the neighbours: summed
      for (int i = 0; i < 8; ++i)
        jbar[jp.node_row[outer.cells(static_cast<Eigen::Index>(c), i)]] += p.jbar[i];
      jbar[jp.first[c]] = p.jbar_centre;
    } else {
      for (int q = 0; q < 8; ++q) jbar[jp.first[c] + q] = p.jbar[q];
    }
    for (const auto& [a, v] : p.source) dsource.row(a) += v.transpose();
  }
  out.volume = weight.sum();
  out.mean = sum / out.volume;
  // ∂J_s/∂(source points) and ∂sd_s/∂(source points), weighted by the samples' bars
  dsource += source_j.surface_vjp(jp.points, jbar) + source_sd.pullback(sd_s, sdbar);
  Eigen::MatrixXd ds = Eigen::MatrixXd::Zero(outer.nodes.rows(), 3), dv = ds;
  samples_adjoint(outer, cells, parts, jp, dj, sd_s, &ds, &dv);
  // mean = S/|Ω_Y|: ∂mean = ∂S/|Ω_Y| − S ∂|Ω_Y|/|Ω_Y|²
  grad->outer = (ds - out.mean * dv) / out.volume;
  grad->source = dsource / out.volume;
  grad->source_volume = dvolume / out.volume;
  return out;
}

}  // namespace softhd::detail

#include "cell_rule.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include "../common/gauss_legendre.hpp"

namespace softhd::detail::cell_rule {

Rule make_rule(const CellDistanceOptions& o, double source_volume) {
  Rule rule;
  gauss_legendre(o.tangential_points, &rule.tx, &rule.tw);
  gauss_legendre(o.panel_points, &rule.px, &rule.pw);
  rule.eps = o.epsilon;
  rule.d0 = o.first_panel * o.epsilon;
  rule.q = o.grading;
  rule.volume = source_volume;
  rule.grade_tangential = o.grade_tangential;
  rule.d0t = o.tangential_first_panel * o.epsilon;
  rule.hybrid = o.hybrid;
  gauss_legendre(o.tangential_panel_points, &rule.qx, &rule.qw);
  return rule;
}

void graded_line(double f, double d0, double q, const std::vector<double>& gx,
                 const std::vector<double>& gw, LineRule* out, bool rates) {
  struct Break {
    double v, df, dd;  // a breakpoint and its rates ∂/∂f, ∂/∂d0
  };
  std::vector<Break> br = {{-1.0, 0.0, 0.0}, {1.0, 0.0, 0.0}};
  if (f > -1.0 && f < 1.0) br.push_back({f, 1.0, 0.0});
  for (int sgn = -1; sgn <= 1; sgn += 2)
    for (double t = d0; t < 4.0; t *= q) {
      const double b = f + sgn * t;  // f ± d0 q^k: ∂/∂d0 = ± q^k = ± t/d0
      if (b > -1.0 && b < 1.0) br.push_back({b, 1.0, sgn * t / d0});
    }
  std::sort(br.begin(), br.end(), [](const Break& a, const Break& b) { return a.v < b.v; });
  out->x.clear(), out->w.clear();
  out->x_f.clear(), out->x_d.clear(), out->w_f.clear(), out->w_d.clear();
  out->graded = true;
  out->d0 = d0;
  Break a = br[0];
  for (std::size_t k = 1; k < br.size(); ++k) {
    const Break b = br[k];
    if (b.v - a.v <= 1e-13) continue;  // a root on an end, within rounding
    for (std::size_t g = 0; g < gx.size(); ++g) {
      // x = a + (b − a)(g + 1)/2, w = (b − a) w_g/2
      out->x.push_back(a.v + 0.5 * (b.v - a.v) * (gx[g] + 1.0));
      out->w.push_back(0.5 * (b.v - a.v) * gw[g]);
      if (!rates) continue;
      const double ca = 0.5 * (1.0 - gx[g]), cb = 0.5 * (1.0 + gx[g]);
      out->x_f.push_back(ca * a.df + cb * b.df);
      out->x_d.push_back(ca * a.dd + cb * b.dd);
      out->w_f.push_back(0.5 * gw[g] * (b.df - a.df));
      out->w_d.push_back(0.5 * gw[g] * (b.dd - a.dd));
    }
    a = b;
  }
}

Root crossing(const Cell& c, const SurfaceDistance& s, double xi[3], int axis, double s0,
              double s1) {
  if (s0 == 0.0) return {-1.0, RootKind::kInside};
  if (s1 == 0.0) return {1.0, RootKind::kInside};
  if ((s0 < 0) == (s1 < 0)) {
    if (s0 == s1) return {1e300, RootKind::kNone};
    return {-1.0 + 2.0 * s0 / (s0 - s1), RootKind::kExtrapolated};
  }
  double a = -1.0, b = 1.0, fa = s0, fb = s1;
  int side = 0;
  for (int it = 0; it < 60 && b - a > 1e-13; ++it) {
    const double m = (a * fb - b * fa) / (fb - fa);
    double x[3];
    xi[axis] = m;
    map_point(c, xi, x, nullptr);
    const double fm = signed_distance(s, x);
    if (fm == 0.0) return {m, RootKind::kInside};
    if ((fm < 0) == (fb < 0)) {
      b = m, fb = fm;
      if (side == -1) fa *= 0.5;
      side = -1;
    } else {
      a = m, fa = fm;
      if (side == 1) fb *= 0.5;
      side = 1;
    }
  }
  return {0.5 * (a + b), RootKind::kInside};
}

void line_ends(const Cell& c, const SurfaceDistance& s, const double xi_line[3], int axis,
               Line* line) {
  double xi[3] = {xi_line[0], xi_line[1], xi_line[2]}, x0[3], x1[3];
  xi[axis] = -1.0;
  map_point(c, xi, x0, nullptr);
  xi[axis] = 1.0;
  map_point(c, xi, x1, nullptr);
  line->s0 = sd_at(s, x0);
  line->s1 = sd_at(s, x1);
  line->length = std::sqrt((x1[0] - x0[0]) * (x1[0] - x0[0]) + (x1[1] - x0[1]) * (x1[1] - x0[1]) +
                           (x1[2] - x0[2]) * (x1[2] - x0[2]));
}

SurfaceDistance::Candidates line_candidates(const Cell& c, const SurfaceDistance& s,
                                            const double xi_line[3], int axis, const Line& line) {
  double xi[3] = {xi_line[0], xi_line[1], xi_line[2]}, x0[3], x1[3];
  xi[axis] = -1.0;
  map_point(c, xi, x0, nullptr);
  xi[axis] = 1.0;
  map_point(c, xi, x1, nullptr);
  const Eigen::Vector3d m(0.5 * (x0[0] + x1[0]), 0.5 * (x0[1] + x1[1]), 0.5 * (x0[2] + x1[2]));
  return s.candidates(m, std::max(std::abs(line.s0.sd), std::abs(line.s1.sd)) + line.length);
}

void line_rule(const Cell& c, const SurfaceDistance& s, const double xi_line[3], int axis,
               double d0, double q, const std::vector<double>& gx, const std::vector<double>& gw,
               const std::vector<double>& fx, const std::vector<double>& fw, Line* line,
               bool rates) {
  double xi[3] = {xi_line[0], xi_line[1], xi_line[2]};
  line->root = crossing(c, s, xi, axis, line->s0.sd, line->s1.sd);
  if (std::abs(line->root.t) <= 2.0) {
    graded_line(line->root.t, 2.0 * d0 / line->length, q, gx, gw, &line->rule, rates);
  } else {
    line->rule.graded = false;
    line->rule.x = fx;
    line->rule.w = fw;
  }
}

int cell_axes(const Cell& c, const SurfaceDistance& s, Line centre[3]) {
  const double zero[3] = {0.0, 0.0, 0.0};
  double change[3];
  for (int k = 0; k < 3; ++k) {
    line_ends(c, s, zero, k, &centre[k]);
    change[k] = std::abs(centre[k].s1.sd - centre[k].s0.sd);
  }
  const double top = std::max({change[0], change[1], change[2]});
  int axis = 0;
  while (change[axis] < top * (1.0 - 1e-9)) ++axis;
  return axis;
}

void tangential_rule(const Cell& c, const SurfaceDistance& s, const Rule& rule, int k, Line* centre,
                     bool rates) {
  if (!rule.grade_tangential) {
    centre->root = Root();
    centre->rule.graded = false;
    centre->rule.x = rule.tx;
    centre->rule.w = rule.tw;
    return;
  }
  const double zero[3] = {0.0, 0.0, 0.0};
  line_rule(c, s, zero, k, rule.d0t, rule.q, rule.qx, rule.qw, rule.tx, rule.tw, centre, rates);
}

Cell cell_of(const HexCells& body, Eigen::Index c) {
  Cell out;
  for (int i = 0; i < 8; ++i)
    for (int d = 0; d < 3; ++d) out.p[i][d] = body.nodes(body.cells(c, i), d);
  return out;
}

void sample_xi(int q, double xi[3]) {
  const double g = 1.0 / std::sqrt(3.0);
  xi[0] = (q & 1) ? g : -g;
  xi[1] = (q & 2) ? g : -g;
  xi[2] = (q & 4) ? g : -g;
}

void cell_samples(const std::vector<Cell>& cells, Eigen::MatrixXd* samples,
                  Eigen::VectorXd* weight) {
  const std::size_t n = cells.size();
  samples->resize(8 * n, 3);
  weight->resize(8 * n);
  for (std::size_t c = 0; c < n; ++c)
    for (int q = 0; q < 8; ++q) {
      double xi[3], x[3], det;
      sample_xi(q, xi);
      map_point(cells[c], xi, x, &det);
      samples->row(8 * c + q) << x[0], x[1], x[2];
      (*weight)[8 * c + q] = det;
    }
}

CellKind cell_kind(const Cell& cell, const SurfaceDistance& s, double near_factor,
                   double corner_factor) {
  // sd at the centre and the corners: a sign change, or the smallest |sd| against the cell's
  // extent along ∇sd there (the direction in which the integrand varies on the scale |sd|)
  const double zero[3] = {0, 0, 0};
  double centre[3];
  map_point(cell, zero, centre, nullptr);
  SignedDistance nearest = sd_at(s, centre);
  bool below = nearest.sd<0.0, above = nearest.sd> 0.0;
  for (int i = 0; i < 8; ++i) {
    const SignedDistance q = sd_at(s, cell.p[i]);
    below = below || q.sd < 0.0;
    above = above || q.sd > 0.0;
    if (std::abs(q.sd) < std::abs(nearest.sd)) nearest = q;
  }
  if (below && above) return CellKind::kNear;
  double lo = 1e300, hi = -1e300;  // the corners' extent along n̂ = ∇sd
  for (int i = 0; i < 8; ++i) {
    const double t = nearest.gradient[0] * cell.p[i][0] + nearest.gradient[1] * cell.p[i][1] +
                     nearest.gradient[2] * cell.p[i][2];
    lo = std::min(lo, t), hi = std::max(hi, t);
  }
  if (std::abs(nearest.sd) <= near_factor * (hi - lo)) return CellKind::kNear;
  // A cell exactly corner_factor extents from the surface (aligned grids: a cell one extent
  // from a coinciding face) keeps the Gauss rule whatever the rounding: the margin, far above
  // the rounding of sd and of the extent, keeps a rigid motion from flipping its rule.
  constexpr double kTieMargin = 1e-9;
  if (corner_factor > 0.0 && std::abs(nearest.sd) >= corner_factor * (hi - lo) * (1 + kTieMargin))
    return CellKind::kCorner;
  return CellKind::kFar;
}

bool is_near(const Cell& cell, const SurfaceDistance& s, double near_factor) {
  return cell_kind(cell, s, near_factor, 0.0) == CellKind::kNear;
}

std::vector<CellKind> cell_kinds(const std::vector<Cell>& cells, const SurfaceDistance& s,
                                 double near_factor, double corner_factor, int threads) {
  std::vector<CellKind> kind(cells.size());
#pragma omp parallel for schedule(dynamic, 16) num_threads(threads)
  for (std::size_t c = 0; c < cells.size(); ++c)
    kind[c] = cell_kind(cells[c], s, near_factor, corner_factor);
  return kind;
}

void corner_rule_weights(const Cell& c, double w[9]) {
  for (int i = 0; i < 8; ++i) {
    const double xi[3] = {double(kSign[i][0]), double(kSign[i][1]), double(kSign[i][2])};
    double x[3];
    map_point(c, xi, x, &w[i]);
    w[i] /= 3.0;
  }
  const double zero[3] = {0, 0, 0};
  double x[3];
  map_point(c, zero, x, &w[8]);
  w[8] *= 16.0 / 3.0;
}

JPoints j_points(const std::vector<Cell>& cells, const std::vector<CellKind>& kind,
                 const Eigen::MatrixXd& samples, const HexCells* body) {
  JPoints out;
  out.first.resize(cells.size());
  Eigen::Index rows = 0;
  if (body) {
    out.node_row.assign(static_cast<std::size_t>(body->nodes.rows()), -1);
    for (std::size_t c = 0; c < cells.size(); ++c)
      if (kind[c] == CellKind::kCorner)
        for (int i = 0; i < 8; ++i) {
          Eigen::Index& r = out.node_row[body->cells(static_cast<Eigen::Index>(c), i)];
          if (r < 0) r = 0;  // marked; numbered in node order below (nearby rows together)
        }
    for (Eigen::Index& r : out.node_row)
      if (r >= 0) r = rows++;
  }
  for (std::size_t c = 0; c < cells.size(); ++c)
    out.first[c] = rows, rows += kind[c] == CellKind::kCorner ? 1 : 8;
  out.points.resize(rows, 3);
  for (std::size_t v = 0; v < out.node_row.size(); ++v)
    if (out.node_row[v] >= 0)
      out.points.row(out.node_row[v]) = body->nodes.row(static_cast<Eigen::Index>(v));
  for (std::size_t c = 0; c < cells.size(); ++c) {
    if (kind[c] != CellKind::kCorner) {
      out.points.middleRows(out.first[c], 8) =
          samples.middleRows(static_cast<Eigen::Index>(8 * c), 8);
      continue;
    }
    const double zero[3] = {0, 0, 0};
    double x[3];
    map_point(cells[c], zero, x, nullptr);
    out.points.row(out.first[c]) << x[0], x[1], x[2];
  }
  return out;
}

double halfspace_slope(double sd, double epsilon) {
  // P = 4π/(3ε) − π/t + πε/(3t²) inside (t = −sd + ε), π/t − πε/(3t²) outside (t = sd + ε):
  // dP/dsd = −π/t² + 2πε/(3t³) on both sides, t = |sd| + ε
  constexpr double kPi = 3.14159265358979323846;
  const double t = std::abs(sd) + epsilon;
  return -kPi / (t * t) + 2.0 * kPi * epsilon / (3.0 * t * t * t);
}

}  // namespace softhd::detail::cell_rule

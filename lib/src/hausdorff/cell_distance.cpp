#include "cell_distance.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <string>
#include <vector>

#include "../common/gauss_legendre.hpp"
#include "../common/surface_bvh.hpp"
#include "body_integral.hpp"
#include "softhd/error.hpp"
#include "softhd/parallel.hpp"

namespace softhd::detail {
namespace {

constexpr double kPi = 3.14159265358979323846;

// The corners' reference signs (Gmsh's order).
constexpr int kSign[8][3] = {{-1, -1, -1}, {1, -1, -1}, {1, 1, -1}, {-1, 1, -1},
                             {-1, -1, 1},  {1, -1, 1},  {1, 1, 1},  {-1, 1, 1}};

// One cell's corners (8 by 3, row-major).
struct Cell {
  double p[8][3];
};

// x(ξ) = Σ_i N_i(ξ) x_i, N_i = Π_k (1 + ξ_k s_ik)/2, and det ∂x/∂ξ.
void map_point(const Cell& c, const double xi[3], double x[3], double* det) {
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

double signed_distance(const SurfaceDistance& s, const double x[3]) {
  return s.at(Eigen::Vector3d(x[0], x[1], x[2])).sd;
}

// d̃^4 = ((J/|Ω_X|)^(−1/4) − ε)^4.
double field4(double j, double source_volume, double eps) {
  const double d = std::pow(j / source_volume, -0.25) - eps;
  const double d2 = d * d;
  return d2 * d2;
}

// Composite Gauss on [−1, 1], panels graded geometrically (first d0, ratio q) on both sides of
// the feature f (inside or outside the interval); appends (ξ, weight).
void graded_line(double f, double d0, double q, const std::vector<double>& gx,
                 const std::vector<double>& gw, std::vector<double>* x, std::vector<double>* w) {
  std::vector<double> br = {-1.0, 1.0};
  if (f > -1.0 && f < 1.0) br.push_back(f);
  for (int sgn = -1; sgn <= 1; sgn += 2)
    for (double t = d0; t < 4.0; t *= q) {
      const double b = f + sgn * t;
      if (b > -1.0 && b < 1.0) br.push_back(b);
    }
  std::sort(br.begin(), br.end());
  double a = br[0];
  for (std::size_t k = 1; k < br.size(); ++k) {
    const double b = br[k];
    if (b - a <= 1e-13) continue;  // a root on an end, within rounding
    for (std::size_t g = 0; g < gx.size(); ++g) {
      x->push_back(a + 0.5 * (b - a) * (gx[g] + 1.0));
      w->push_back(0.5 * (b - a) * gw[g]);
    }
    a = b;
  }
}

// Where sd crosses 0 on the reference line ξ_axis ∈ [−1, 1] (the other two coordinates in
// xi): Illinois regula falsi inside, the linear extrapolation of the ends' values outside
// (returned as is; a value beyond ±2 means no crossing within half a cell).
double crossing(const Cell& c, const SurfaceDistance& s, double xi[3], int axis, double s0,
                double s1) {
  if (s0 == 0.0) return -1.0;
  if (s1 == 0.0) return 1.0;
  if ((s0 < 0) == (s1 < 0)) return s0 == s1 ? 1e300 : -1.0 + 2.0 * s0 / (s0 - s1);
  double a = -1.0, b = 1.0, fa = s0, fb = s1;
  int side = 0;
  for (int it = 0; it < 60 && b - a > 1e-13; ++it) {
    const double m = (a * fb - b * fa) / (fb - fa);
    double x[3];
    xi[axis] = m;
    map_point(c, xi, x, nullptr);
    const double fm = signed_distance(s, x);
    if (fm == 0.0) return m;
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
  return 0.5 * (a + b);
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

// f(ξ) trilinear through the samples at ξ_k = ±1/√3 (sample g = i + 2j + 4k).
double interpolate(const double f[8], const double xi[3]) {
  const double r3 = std::sqrt(3.0);
  double t[3];
  for (int k = 0; k < 3; ++k) t[k] = 0.5 * (xi[k] * r3 + 1.0);
  double v = 0.0;
  for (int g = 0; g < 8; ++g) {
    double wgt = 1.0;
    for (int k = 0; k < 3; ++k) wgt *= ((g >> k) & 1) ? t[k] : 1.0 - t[k];
    v += wgt * f[g];
  }
  return v;
}

// J at a point of a near cell from the profile P = P_ε(sd) there: the factor, P · exp(f); with
// `hybrid` the difference, P + g, where it changes P by at most half (just outside the source J
// = P − M with M, the mass the half-space has and the source lacks, smooth across the surface,
// where f = log(1 − M/P) has a kink), else the factor.
double model_j(double p, const double f[8], const double g[8], const double xi[3], bool hybrid) {
  if (hybrid) {
    const double d = interpolate(g, xi);
    if (std::abs(d) <= 0.5 * p) return p + d;
  }
  return p * std::exp(interpolate(f, xi));
}

// ∫_cell d̃^4 by the graded rule (J = P_ε(sd) exp(f)); counts its points.
double near_cell(const Cell& c, const double f[8], const double g[8], const SurfaceDistance& s,
                 const Rule& r, long* points) {
  // The axis along which sd changes most between opposite face centres (ties: the first).
  double change[3], ends[3][2], length[3];
  for (int k = 0; k < 3; ++k) {
    double xi[3] = {0, 0, 0}, x0[3], x1[3];
    xi[k] = -1.0;
    map_point(c, xi, x0, nullptr);
    xi[k] = 1.0;
    map_point(c, xi, x1, nullptr);
    ends[k][0] = signed_distance(s, x0), ends[k][1] = signed_distance(s, x1);
    change[k] = std::abs(ends[k][1] - ends[k][0]);
    length[k] = std::sqrt((x1[0] - x0[0]) * (x1[0] - x0[0]) + (x1[1] - x0[1]) * (x1[1] - x0[1]) +
                          (x1[2] - x0[2]) * (x1[2] - x0[2]));
  }
  const double top = std::max({change[0], change[1], change[2]});
  int axis = 0;
  while (change[axis] < top * (1.0 - 1e-9)) ++axis;
  const int b = (axis + 1) % 3, e = (axis + 2) % 3;
  // The tangential rules: Gauss, or graded towards the crossing of the cell's centre line along
  // that axis (an edge or corner of the source in the cell) when r.grade_tangential.
  std::vector<double> bx = r.tx, bw = r.tw, ex = r.tx, ew = r.tw;
  for (int k : {b, e}) {
    if (!r.grade_tangential) break;
    double xi[3] = {0, 0, 0};
    const double root = crossing(c, s, xi, k, ends[k][0], ends[k][1]);
    if (std::abs(root) > 2.0) continue;
    std::vector<double>& gx = k == b ? bx : ex;
    std::vector<double>& gw = k == b ? bw : ew;
    gx.clear(), gw.clear();
    graded_line(root, 2.0 * r.d0t / length[k], r.q, r.qx, r.qw, &gx, &gw);
  }
  double sum = 0.0;
  std::vector<double> lx, lw;
  for (std::size_t i = 0; i < bx.size(); ++i)
    for (std::size_t j = 0; j < ex.size(); ++j) {
      double xi[3], x0[3], x1[3];
      xi[b] = bx[i], xi[e] = ex[j];
      xi[axis] = -1.0;
      map_point(c, xi, x0, nullptr);
      xi[axis] = 1.0;
      map_point(c, xi, x1, nullptr);
      const double s0 = signed_distance(s, x0), s1 = signed_distance(s, x1);
      const double len =
          std::sqrt((x1[0] - x0[0]) * (x1[0] - x0[0]) + (x1[1] - x0[1]) * (x1[1] - x0[1]) +
                    (x1[2] - x0[2]) * (x1[2] - x0[2]));
      const double root = crossing(c, s, xi, axis, s0, s1);
      lx.clear(), lw.clear();
      if (std::abs(root) <= 2.0) {
        graded_line(root, 2.0 * r.d0 / len, r.q, r.px, r.pw, &lx, &lw);
      } else {
        lx = r.px, lw = r.pw;
      }
      for (std::size_t k = 0; k < lx.size(); ++k) {
        xi[axis] = lx[k];
        double x[3], det;
        map_point(c, xi, x, &det);
        double j_y;
        if (r.exact) {
          Eigen::VectorXd v;
          r.exact->evaluate(Eigen::RowVector3d(x[0], x[1], x[2]), &v);
          j_y = v[0];
        } else {
          j_y = model_j(halfspace_profile(signed_distance(s, x), r.eps), f, g, xi, r.hybrid);
        }
        sum += bw[i] * ew[j] * lw[k] * det * field4(j_y, r.volume, r.eps);
      }
      *points += static_cast<long>(lx.size());
    }
  return sum;
}

Cell cell_of(const HexCells& body, Eigen::Index c) {
  Cell out;
  for (int i = 0; i < 8; ++i)
    for (int d = 0; d < 3; ++d) out.p[i][d] = body.nodes(body.cells(c, i), d);
  return out;
}

void check_cells(const HexCells& body) {
  if (body.nodes.cols() != 3) throw InvalidArgument("hex cells: nodes must be N by 3");
  for (Eigen::Index c = 0; c < body.cells.rows(); ++c)
    for (int i = 0; i < 8; ++i)
      if (body.cells(c, i) < 0 || body.cells(c, i) >= body.nodes.rows())
        throw InvalidArgument("hex cells: cell " + std::to_string(c) + " names node " +
                              std::to_string(body.cells(c, i)) + ", out of range");
}

}  // namespace

void CellDistanceOptions::validate() const {
  auto bad = [](const char* field) {
    throw InvalidArgument(std::string("cell distance options: invalid ") + field);
  };
  if (!(epsilon > 0.0) || !std::isfinite(epsilon)) bad("epsilon (> 0)");
  if (tangential_points < 1 || tangential_points > 64) bad("tangential_points (1 to 64)");
  if (panel_points < 1 || panel_points > 64) bad("panel_points (1 to 64)");
  if (!(first_panel > 0.0) || !std::isfinite(first_panel)) bad("first_panel (> 0)");
  if (!(grading > 1.0) || !std::isfinite(grading)) bad("grading (> 1)");
  if (!(tangential_first_panel > 0.0) || !std::isfinite(tangential_first_panel))
    bad("tangential_first_panel (> 0)");
  if (tangential_panel_points < 1 || tangential_panel_points > 64)
    bad("tangential_panel_points (1 to 64)");
  if (refine_crossed < 0 || refine_crossed > 4) bad("refine_crossed (0 to 4)");
  if (!(near_factor >= 0.0) || !std::isfinite(near_factor)) bad("near_factor (>= 0)");
  if (!(tolerance >= 0.0 && tolerance < 1.0)) bad("tolerance (0 to 1)");
  if (!(j_near_ratio >= 1.0) || !std::isfinite(j_near_ratio)) bad("j_near_ratio (>= 1)");
  if (j_angle_points < 2 || j_angle_points > 64) bad("j_angle_points (2 to 64)");
  check_threads(threads);
}

double halfspace_profile(double sd, double epsilon) {
  // inside (d = −sd ≥ 0): 4π/(3ε) − π/(d + ε) + πε/(3(d + ε)²); outside: π/(D + ε) − πε/(3(D + ε)²)
  if (sd < 0.0) {
    const double t = -sd + epsilon;
    return 4.0 * kPi / (3.0 * epsilon) - kPi / t + kPi * epsilon / (3.0 * t * t);
  }
  const double t = sd + epsilon;
  return kPi / t - kPi * epsilon / (3.0 * t * t);
}

TriangleSurface hex_boundary(const HexCells& body) {
  check_cells(body);
  // The outward faces in Gmsh's corner order.
  constexpr int kFace[6][4] = {{0, 3, 2, 1}, {0, 1, 5, 4}, {0, 4, 7, 3},
                               {1, 2, 6, 5}, {2, 3, 7, 6}, {4, 5, 6, 7}};
  std::map<std::array<int, 4>, std::pair<int, std::array<int, 4>>> faces;  // sorted → (count, face)
  for (Eigen::Index c = 0; c < body.cells.rows(); ++c)
    for (const auto& f : kFace) {
      std::array<int, 4> q, key;
      for (int k = 0; k < 4; ++k) q[k] = body.cells(c, f[k]);
      key = q;
      std::sort(key.begin(), key.end());
      auto& slot = faces[key];
      slot.first += 1;
      slot.second = q;
    }
  std::vector<int> id(body.nodes.rows(), -1);
  std::vector<std::array<int, 3>> tris;
  int used = 0;
  for (const auto& kv : faces) {
    if (kv.second.first != 1) continue;
    std::array<int, 4> q = kv.second.second;
    for (int& v : q) {
      if (id[v] < 0) id[v] = used++;
      v = id[v];
    }
    tris.push_back({q[0], q[1], q[2]});
    tris.push_back({q[0], q[2], q[3]});
  }
  TriangleSurface s;
  s.points.resize(used, 3);
  for (Eigen::Index v = 0; v < body.nodes.rows(); ++v)
    if (id[v] >= 0) s.points.row(id[v]) = body.nodes.row(v);
  s.triangles.resize(static_cast<Eigen::Index>(tris.size()), 3);
  for (std::size_t t = 0; t < tris.size(); ++t)
    for (int k = 0; k < 3; ++k) s.triangles(t, k) = tris[t][k];
  return s;
}

HexCells hex_cube(const Eigen::Vector3d& lo, double side, int n) {
  if (n < 1) throw InvalidArgument("hex cube: n must be >= 1");
  HexCells b;
  const int m = n + 1;
  b.nodes.resize(m * m * m, 3);
  for (int k = 0; k < m; ++k)
    for (int j = 0; j < m; ++j)
      for (int i = 0; i < m; ++i)
        b.nodes.row((k * m + j) * m + i) = lo.transpose() + side / n * Eigen::RowVector3d(i, j, k);
  b.cells.resize(n * n * n, 8);
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i)
        for (int c = 0; c < 8; ++c) {
          const int ii = i + (kSign[c][0] > 0), jj = j + (kSign[c][1] > 0),
                    kk = k + (kSign[c][2] > 0);
          b.cells((k * n + j) * n + i, c) = (kk * m + jj) * m + ii;
        }
  return b;
}

double enclosed_volume(const TriangleSurface& s) {
  // |Ω| = Σ_t a·(b × c)/6 (the divergence theorem with F = x/3)
  double v = 0.0;
  for (Eigen::Index t = 0; t < s.triangles.rows(); ++t) {
    const Eigen::Vector3d a = s.points.row(s.triangles(t, 0)), b = s.points.row(s.triangles(t, 1)),
                          c = s.points.row(s.triangles(t, 2));
    v += a.dot(b.cross(c));
  }
  return v / 6.0;
}

namespace {

// The source a directed mean integrates against.
struct Source {
  const BodyIntegral& j;
  const SurfaceDistance& sd;
};

// The 8 children of a cell (ξ_k ∈ [−1, 0] or [0, 1]): a trilinear map restricted to a sub-box is
// trilinear again.
void split_cell(const Cell& c, std::vector<Cell>* out) {
  for (int child = 0; child < 8; ++child) {
    Cell k;
    for (int i = 0; i < 8; ++i) {
      double xi[3];
      for (int a = 0; a < 3; ++a) xi[a] = (((child >> a) & 1) ? 0.5 : -0.5) + 0.5 * kSign[i][a];
      map_point(c, xi, k.p[i], nullptr);
    }
    out->push_back(k);
  }
}

// Whether sd changes sign over the cell's corners and samples (the surface crosses it).
bool crossed(const Cell& c, const SurfaceDistance& s, const std::vector<SignedDistance>& sd_s,
             std::size_t first) {
  int neg = 0, pos = 0;
  for (int i = 0; i < 8; ++i) {
    const double v = signed_distance(s, c.p[i]);
    const double w = sd_s[first + i].sd;
    neg += (v <= 0) + (w <= 0);
    pos += (v >= 0) + (w >= 0);
  }
  return neg > 0 && pos > 0;
}

// Σ over the cells of ∫_cell d̃^4 (the rule of the header); the near cells the surface crosses
// are split into 8 children with samples of their own while level < refine_crossed.
double sum_cells(const std::vector<Cell>& cells, const Source& src, const Rule& rule,
                 const CellDistanceOptions& o, int level, OuterMean* out) {
  const std::size_t n = cells.size();
  const double g = 1.0 / std::sqrt(3.0);
  Eigen::MatrixXd samples(8 * n, 3);  // every cell's 2×2×2 Gauss points, weights det J
  Eigen::VectorXd weight(8 * n);
  for (std::size_t c = 0; c < n; ++c)
    for (int q = 0; q < 8; ++q) {
      const double xi[3] = {(q & 1) ? g : -g, (q & 2) ? g : -g, (q & 4) ? g : -g};
      double x[3], det;
      map_point(cells[c], xi, x, &det);
      samples.row(8 * c + q) << x[0], x[1], x[2];
      weight[8 * c + q] = det;
    }
  Eigen::VectorXd j_s;
  src.j.evaluate(samples, &j_s);
  const int threads = resolve_threads(o.threads);
  const std::vector<SignedDistance> sd_s = src.sd.at_rows(samples, threads);
  std::vector<double> part(n, 0.0);
  std::vector<long> near(n, 0), points(n, 0);
  std::vector<char> split(n, 0);
#pragma omp parallel for schedule(dynamic, 4) num_threads(threads)
  for (std::size_t c = 0; c < n; ++c) {
    const Cell& cell = cells[c];
    double centre[3];
    const double zero[3] = {0, 0, 0};
    map_point(cell, zero, centre, nullptr);
    double diameter = 0.0;  // the longest body diagonal
    for (int i = 0; i < 4; ++i) {
      double d2 = 0.0;
      for (int d = 0; d < 3; ++d)
        d2 += std::pow(cell.p[i][d] - cell.p[(i < 2 ? i + 6 : i + 2)][d], 2);
      diameter = std::max(diameter, std::sqrt(d2));
    }
    if (std::abs(signed_distance(src.sd, centre)) > o.near_factor * diameter) {
      for (int q = 0; q < 8; ++q)
        part[c] += weight[8 * c + q] * field4(j_s[8 * c + q], rule.volume, o.epsilon);
      continue;
    }
    if (level < o.refine_crossed && crossed(cell, src.sd, sd_s, 8 * c)) {
      split[c] = 1;
      continue;
    }
    double f[8], gd[8];  // f_s = log(J_s / P_ε(sd_s)), g_s = J_s − P_ε(sd_s)
    for (int q = 0; q < 8; ++q) {
      const double p = halfspace_profile(sd_s[8 * c + q].sd, o.epsilon);
      f[q] = std::log(j_s[8 * c + q] / p);
      gd[q] = j_s[8 * c + q] - p;
    }
    near[c] = 1;
    part[c] = near_cell(cell, f, gd, src.sd, rule, &points[c]);
  }
  double sum = 0.0;
  std::vector<Cell> children;
  for (std::size_t c = 0; c < n; ++c) {
    sum += part[c];
    out->near_cells += near[c];
    out->near_points += points[c];
    if (split[c]) split_cell(cells[c], &children);
  }
  if (level == 0) out->volume = weight.sum();
  if (!children.empty()) sum += sum_cells(children, src, rule, o, level + 1, out);
  return sum;
}

}  // namespace

OuterMean directed_outer_mean(const HexCells& outer, const BodyIntegral& source_j,
                              const SurfaceDistance& source_sd, double source_volume,
                              const CellDistanceOptions& options) {
  options.validate();
  check_cells(outer);
  Rule rule;
  gauss_legendre(options.tangential_points, &rule.tx, &rule.tw);
  gauss_legendre(options.panel_points, &rule.px, &rule.pw);
  rule.eps = options.epsilon;
  rule.d0 = options.first_panel * options.epsilon;
  rule.q = options.grading;
  rule.volume = source_volume;
  rule.grade_tangential = options.grade_tangential;
  rule.d0t = options.tangential_first_panel * options.epsilon;
  if (options.exact_near) rule.exact = &source_j;
  rule.hybrid = options.hybrid;
  gauss_legendre(options.tangential_panel_points, &rule.qx, &rule.qw);
  std::vector<Cell> cells;
  for (Eigen::Index c = 0; c < outer.cells.rows(); ++c) cells.push_back(cell_of(outer, c));
  OuterMean out;
  const double sum = sum_cells(cells, Source{source_j, source_sd}, rule, options, 0, &out);
  out.mean = sum / out.volume;
  return out;
}

CellRho cell_rho(const HexCells& x, const HexCells& y, const CellDistanceOptions& options) {
  options.validate();
  BodyIntegralOptions bo;
  bo.epsilon = options.epsilon;
  bo.alpha = 4.0;
  bo.threads = options.threads;
  bo.tolerance = options.tolerance;
  bo.near_ratio = options.j_near_ratio;
  bo.angle_points = options.j_angle_points;
  const TriangleSurface sx = hex_boundary(x), sy = hex_boundary(y);
  const BodyIntegral jx(sx, bo), jy(sy, bo);
  const SurfaceDistance dx(sx), dy(sy);
  CellRho r;
  r.a = directed_outer_mean(y, jx, dx, enclosed_volume(sx), options);
  r.b = directed_outer_mean(x, jy, dy, enclosed_volume(sy), options);
  // ρ̃ = ((A² + B²)/2)^(1/2), A = (A^4)^(1/4)
  r.rho = std::sqrt(0.5 * (std::sqrt(r.a.mean) + std::sqrt(r.b.mean)));
  return r;
}

}  // namespace softhd::detail

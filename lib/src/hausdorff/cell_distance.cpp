#include "cell_distance.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <string>
#include <vector>

#include "../common/surface_bvh.hpp"
#include "body_integral.hpp"
#include "cell_rule.hpp"
#include "softhd/error.hpp"
#include "softhd/parallel.hpp"

namespace softhd::detail {
namespace {

constexpr double kPi = 3.14159265358979323846;

using cell_rule::Cell;
using cell_rule::field4;
using cell_rule::interpolate;
using cell_rule::kSign;
using cell_rule::Line;
using cell_rule::map_point;
using cell_rule::Rule;
using cell_rule::signed_distance;

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
  Line centre[3];  // the centre lines: the axis along which sd changes most, the tangential rules
  const int axis = cell_rule::cell_axes(c, s, centre);
  const int b = (axis + 1) % 3, e = (axis + 2) % 3;
  cell_rule::tangential_rule(c, s, r, b, &centre[b], false);
  cell_rule::tangential_rule(c, s, r, e, &centre[e], false);
  const std::vector<double>&bx = centre[b].rule.x, &bw = centre[b].rule.w;
  const std::vector<double>&ex = centre[e].rule.x, &ew = centre[e].rule.w;
  double sum = 0.0;
  Line line;
  for (std::size_t i = 0; i < bx.size(); ++i)
    for (std::size_t j = 0; j < ex.size(); ++j) {
      double xi[3];
      xi[b] = bx[i], xi[e] = ex[j], xi[axis] = 0.0;
      cell_rule::line_ends(c, s, xi, axis, &line);
      cell_rule::line_rule(c, s, xi, axis, r.d0, r.q, r.px, r.pw, r.px, r.pw, &line, false);
      const std::vector<double>&lx = line.rule.x, &lw = line.rule.w;
      const SurfaceDistance::Candidates near = cell_rule::line_candidates(c, s, xi, axis, line);
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
          j_y = model_j(halfspace_profile(cell_rule::sd_at(s, x, near).sd, r.eps), f, g, xi,
                        r.hybrid);
        }
        sum += bw[i] * ew[j] * lw[k] * det * field4(j_y, r.volume, r.eps);
      }
      *points += static_cast<long>(lx.size());
    }
  return sum;
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
  if (!(corner_factor >= 0.0) || !std::isfinite(corner_factor)) bad("corner_factor (>= 0)");
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

TriangleSurface hex_boundary(const HexCells& body, std::vector<int>* point_node) {
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
  if (point_node) point_node->assign(static_cast<std::size_t>(used), -1);
  for (Eigen::Index v = 0; v < body.nodes.rows(); ++v)
    if (id[v] >= 0) {
      s.points.row(id[v]) = body.nodes.row(v);
      if (point_node) (*point_node)[static_cast<std::size_t>(id[v])] = static_cast<int>(v);
    }
  s.triangles.resize(static_cast<Eigen::Index>(tris.size()), 3);
  for (std::size_t t = 0; t < tris.size(); ++t)
    for (int k = 0; k < 3; ++k) s.triangles(t, k) = tris[t][k];
  return s;
}

HexCells hex_box(const Eigen::Vector3d& lo, const Eigen::Vector3d& size, const Eigen::Vector3i& n) {
  if (n.minCoeff() < 1) throw InvalidArgument("hex box: the cell counts must be >= 1");
  HexCells b;
  const Eigen::Vector3i m = n.array() + 1;
  b.nodes.resize(m.prod(), 3);
  for (int k = 0; k < m[2]; ++k)
    for (int j = 0; j < m[1]; ++j)
      for (int i = 0; i < m[0]; ++i)
        for (int d = 0; d < 3; ++d)
          b.nodes((k * m[1] + j) * m[0] + i, d) =
              lo[d] + size[d] * Eigen::Vector3i(i, j, k)[d] / n[d];
  b.cells.resize(n.prod(), 8);
  for (int k = 0; k < n[2]; ++k)
    for (int j = 0; j < n[1]; ++j)
      for (int i = 0; i < n[0]; ++i)
        for (int c = 0; c < 8; ++c) {
          const int ii = i + (kSign[c][0] > 0), jj = j + (kSign[c][1] > 0),
                    kk = k + (kSign[c][2] > 0);
          b.cells((k * n[1] + j) * n[0] + i, c) = (kk * m[1] + jj) * m[0] + ii;
        }
  return b;
}

HexCells hex_cube(const Eigen::Vector3d& lo, double side, int n) {
  if (n < 1) throw InvalidArgument("hex cube: n must be >= 1");
  return hex_box(lo, Eigen::Vector3d::Constant(side), Eigen::Vector3i::Constant(n));
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

Eigen::MatrixXd enclosed_volume_gradient(const TriangleSurface& s) {
  // ∂/∂a of a·(b × c)/6 = (b × c)/6, ∂/∂b = (c × a)/6, ∂/∂c = (a × b)/6
  Eigen::MatrixXd g = Eigen::MatrixXd::Zero(s.points.rows(), 3);
  for (Eigen::Index t = 0; t < s.triangles.rows(); ++t) {
    const Eigen::Vector3d a = s.points.row(s.triangles(t, 0)), b = s.points.row(s.triangles(t, 1)),
                          c = s.points.row(s.triangles(t, 2));
    g.row(s.triangles(t, 0)) += b.cross(c).transpose() / 6.0;
    g.row(s.triangles(t, 1)) += c.cross(a).transpose() / 6.0;
    g.row(s.triangles(t, 2)) += a.cross(b).transpose() / 6.0;
  }
  return g;
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

// node_samples: J at the distinct corners of `cells`, then per cell the factor at its 8 Gauss
// points from the trilinear through its corners, f(ξ_q) = Σ_i N_i(ξ_q) log(J_i/P_ε(sd_i)), and
// J_q = P_ε(sd_q) exp(f(ξ_q)) at the samples (sd_q exact). Overwrites j_s (8 per cell).
void corner_samples(const std::vector<Cell>& cells, const Source& src, const CellDistanceOptions& o,
                    const std::vector<SignedDistance>& sd_s, Eigen::VectorXd* j_s) {
  std::map<std::array<double, 3>, int> id;
  std::vector<std::array<double, 3>> points;
  std::vector<int> corner(8 * cells.size());
  for (std::size_t c = 0; c < cells.size(); ++c)
    for (int i = 0; i < 8; ++i) {
      const std::array<double, 3> p = {cells[c].p[i][0], cells[c].p[i][1], cells[c].p[i][2]};
      auto it = id.emplace(p, static_cast<int>(points.size())).first;
      if (it->second == static_cast<int>(points.size())) points.push_back(p);
      corner[8 * c + i] = it->second;
    }
  Eigen::MatrixXd y(static_cast<Eigen::Index>(points.size()), 3);
  for (std::size_t k = 0; k < points.size(); ++k)
    y.row(k) << points[k][0], points[k][1], points[k][2];
  Eigen::VectorXd j;
  src.j.evaluate(y, &j);
  const std::vector<SignedDistance> sd = src.sd.at_rows(y, resolve_threads(o.threads));
  for (std::size_t c = 0; c < cells.size(); ++c)
    for (int q = 0; q < 8; ++q) {
      double xi[3], f = 0.0;
      cell_rule::sample_xi(q, xi);
      for (int i = 0; i < 8; ++i) {
        double n = 1.0;  // N_i(ξ) = Π_k (1 + ξ_k s_ik)/2
        for (int k = 0; k < 3; ++k) n *= 0.5 * (1.0 + xi[k] * kSign[i][k]);
        const int v = corner[8 * c + i];
        f += n * std::log(j[v] / halfspace_profile(sd[v].sd, o.epsilon));
      }
      (*j_s)[8 * c + q] = halfspace_profile(sd_s[8 * c + q].sd, o.epsilon) * std::exp(f);
    }
}

// ∫_cell d̃^4 by the corner rule: Σ_i (det J(ξ_i)/3) F(J(x_i)) + (16 det J(0)/3) F(J(x(0))),
// j_corner[i] = J at corner i, j_centre at the centre.
double corner_cell(const Cell& cell, const double j_corner[8], double j_centre, double volume,
                   double eps) {
  double w[9], sum = 0.0;
  cell_rule::corner_rule_weights(cell, w);
  for (int i = 0; i < 8; ++i) sum += w[i] * field4(j_corner[i], volume, eps);
  return sum + w[8] * field4(j_centre, volume, eps);
}

// Σ over the cells of ∫_cell d̃^4 (the rule of the header); the near cells the surface crosses
// are split into 8 children with samples of their own while level < refine_crossed.
double sum_cells(const std::vector<Cell>& cells, const HexCells* body, const Source& src,
                 const Rule& rule, const CellDistanceOptions& o, int level, OuterMean* out) {
  const std::size_t n = cells.size();
  Eigen::MatrixXd samples;  // every cell's 2×2×2 Gauss points, weights det J
  Eigen::VectorXd weight;
  cell_rule::cell_samples(cells, &samples, &weight);
  const int threads = resolve_threads(o.threads);
  const bool corners = level == 0 && !o.node_samples;  // the mesh's node ids: level 0 only
  const std::vector<cell_rule::CellKind> kind =
      cell_rule::cell_kinds(cells, src.sd, o.near_factor, corners ? o.corner_factor : 0.0, threads);
  const cell_rule::JPoints jp = cell_rule::j_points(cells, kind, samples, corners ? body : nullptr);
  Eigen::VectorXd j_all(samples.rows());  // J at the rows of jp (8 per cell with node_samples)
  const std::vector<SignedDistance> sd_s = src.sd.at_rows(samples, threads);
  if (o.node_samples)
    corner_samples(cells, src, o, sd_s, &j_all);
  else
    src.j.evaluate(jp.points, &j_all);
  std::vector<double> part(n, 0.0);
  std::vector<long> near(n, 0), points(n, 0), corner(n, 0);
  std::vector<char> split(n, 0);
#pragma omp parallel for schedule(dynamic, 4) num_threads(threads)
  for (std::size_t c = 0; c < n; ++c) {
    const Cell& cell = cells[c];
    const double* j_s = &j_all[jp.first[c]];  // the cell's J: 8 samples, or its centre
    if (kind[c] == cell_rule::CellKind::kCorner) {
      corner[c] = 1;
      double j_corner[8];
      for (int i = 0; i < 8; ++i)
        j_corner[i] = j_all[jp.node_row[body->cells(static_cast<Eigen::Index>(c), i)]];
      part[c] = corner_cell(cell, j_corner, j_s[0], rule.volume, o.epsilon);
      continue;
    }
    if (kind[c] == cell_rule::CellKind::kFar) {
      for (int q = 0; q < 8; ++q)
        part[c] += weight[8 * c + q] * field4(j_s[q], rule.volume, o.epsilon);
      continue;
    }
    if (level < o.refine_crossed && crossed(cell, src.sd, sd_s, 8 * c)) {
      split[c] = 1;
      continue;
    }
    double f[8], gd[8];  // f_s = log(J_s / P_ε(sd_s)), g_s = J_s − P_ε(sd_s)
    for (int q = 0; q < 8; ++q) {
      const double p = halfspace_profile(sd_s[8 * c + q].sd, o.epsilon);
      f[q] = std::log(j_s[q] / p);
      gd[q] = j_s[q] - p;
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
    out->corner_cells += corner[c];
    if (split[c]) split_cell(cells[c], &children);
  }
  if (level == 0) out->volume = weight.sum();
  if (!children.empty()) sum += sum_cells(children, nullptr, src, rule, o, level + 1, out);
  return sum;
}

}  // namespace

OuterMean directed_outer_mean(const HexCells& outer, const BodyIntegral& source_j,
                              const SurfaceDistance& source_sd, double source_volume,
                              const CellDistanceOptions& options, OuterMeanGradient* grad) {
  options.validate();
  check_cells(outer);
  if (grad)
    return outer_mean_with_gradient(outer, source_j, source_sd, source_volume, options, grad);
  Rule rule = cell_rule::make_rule(options, source_volume);
  if (options.exact_near) rule.exact = &source_j;
  std::vector<Cell> cells;
  for (Eigen::Index c = 0; c < outer.cells.rows(); ++c)
    cells.push_back(cell_rule::cell_of(outer, c));
  OuterMean out;
  const double sum = sum_cells(cells, &outer, Source{source_j, source_sd}, rule, options, 0, &out);
  out.mean = sum / out.volume;
  return out;
}

namespace {}  // namespace

// The bars of a directed mean on the source's surface points (through J, sd and |Ω_X|), times
// scale, added to the source's nodes (point_node: the surface point → node map).
void add_source_bars(const OuterMeanGradient& g, double scale, const TriangleSurface& surface,
                     const std::vector<int>& point_node, Eigen::MatrixXd* nodes) {
  const Eigen::MatrixXd bars =
      g.source + g.source_volume * enclosed_volume_gradient(surface);  // ∂|Ω_X|/∂points
  for (Eigen::Index a = 0; a < bars.rows(); ++a)
    nodes->row(point_node[static_cast<std::size_t>(a)]) += scale * bars.row(a);
}

double combine_means(CellRho* r, double* ca, double* cb) {
  // ρ̃ = ((A² + B²)/2)^(1/2), A = (A^4)^(1/4); ∂ρ̃/∂A^4 = 1/(8 ρ̃ √(A^4)), likewise B
  r->rho = std::sqrt(0.5 * (std::sqrt(r->a.mean) + std::sqrt(r->b.mean)));
  if (ca) *ca = 1.0 / (8.0 * r->rho * std::sqrt(r->a.mean));
  if (cb) *cb = 1.0 / (8.0 * r->rho * std::sqrt(r->b.mean));
  return r->rho;
}

BodyIntegralOptions body_integral_options(const CellDistanceOptions& options) {
  BodyIntegralOptions bo;
  bo.epsilon = options.epsilon;
  bo.alpha = 4.0;
  bo.threads = options.threads;
  bo.tolerance = options.tolerance;
  bo.near_ratio = options.j_near_ratio;
  bo.angle_points = options.j_angle_points;
  return bo;
}

CellRho cell_rho(const HexCells& x, const HexCells& y, const CellDistanceOptions& options,
                 CellRhoGradient* grad) {
  options.validate();
  const BodyIntegralOptions bo = body_integral_options(options);
  std::vector<int> node_x, node_y;
  const TriangleSurface sx = hex_boundary(x, &node_x), sy = hex_boundary(y, &node_y);
  const BodyIntegral jx(sx, bo), jy(sy, bo);
  const SurfaceDistance dx(sx), dy(sy);
  CellRho r;
  OuterMeanGradient ga, gb;
  r.a = directed_outer_mean(y, jx, dx, enclosed_volume(sx), options, grad ? &ga : nullptr);
  r.b = directed_outer_mean(x, jy, dy, enclosed_volume(sy), options, grad ? &gb : nullptr);
  double ca = 0.0, cb = 0.0;
  combine_means(&r, &ca, &cb);
  if (!grad) return r;
  grad->y = ca * ga.outer;
  grad->x = cb * gb.outer;
  add_source_bars(ga, ca, sx, node_x, &grad->x);
  add_source_bars(gb, cb, sy, node_y, &grad->y);
  return r;
}

}  // namespace softhd::detail

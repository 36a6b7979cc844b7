#include "cell_form.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <string>

#include "../common/surface_bvh.hpp"
#include "../hausdorff/body_integral.hpp"
#include "../hausdorff/surface_mean.hpp"
#include "softhd/error.hpp"
#include "softhd/scan/pose_map.hpp"

namespace softhd::detail {

namespace {

HexCells hex_cells(const fe::HexDecomposition& d, const Eigen::MatrixXd& nodes) {
  return {d.map * nodes, d.cells};
}

void check_3d(const fe::Mesh& mesh, const char* which) {
  if (mesh.dim != 3)
    throw InvalidArgument(std::string("quadrature cells: the ") + which +
                          " is 2D; the cell quadrature is 3D only (not yet 2D)");
}

// d̃ = (J/|Ω|)^(−1/4) − ε (α = 4) at every row of `points` against a body's J.
Eigen::VectorXd d_tilde(const BodyIntegral& j, double volume, double epsilon,
                        const Eigen::MatrixXd& points) {
  Eigen::VectorXd v;
  j.evaluate(points, &v);
  for (Eigen::Index k = 0; k < v.size(); ++k) v[k] = std::pow(v[k] / volume, -0.25) - epsilon;
  return v;
}

// Morton's interleaving of three 10-bit integers: ordering points by it keeps consecutive rows
// close together, as BodyIntegral's grouped traversal wants.
std::uint32_t morton(std::uint32_t x, std::uint32_t y, std::uint32_t z) {
  std::uint32_t key = 0;
  for (int b = 0; b < 10; ++b)
    key |= ((x >> b) & 1u) << (3 * b) | ((y >> b) & 1u) << (3 * b + 1) |
           ((z >> b) & 1u) << (3 * b + 2);
  return key;
}

// The rows of `points` (M by 3) in Morton order on a 1024³ grid over their bounding box.
std::vector<Eigen::Index> by_place(const Eigen::MatrixXd& points) {
  const Eigen::RowVector3d lo = points.colwise().minCoeff();
  const double span = std::max((points.colwise().maxCoeff() - lo).maxCoeff(), 1e-300);
  std::vector<std::uint32_t> key(static_cast<std::size_t>(points.rows()));
  for (Eigen::Index k = 0; k < points.rows(); ++k) {
    const Eigen::RowVector3d c = (points.row(k) - lo) / span * 1023.0;
    key[static_cast<std::size_t>(k)] =
        morton(static_cast<std::uint32_t>(c[0]), static_cast<std::uint32_t>(c[1]),
               static_cast<std::uint32_t>(c[2]));
  }
  std::vector<Eigen::Index> order(key.size());
  std::iota(order.begin(), order.end(), Eigen::Index{0});
  std::stable_sort(order.begin(), order.end(), [&key](Eigen::Index a, Eigen::Index b) {
    return key[static_cast<std::size_t>(a)] < key[static_cast<std::size_t>(b)];
  });
  return order;
}

}  // namespace

CellForm::CellForm(const fe::Mesh& body, const Eigen::MatrixXd& points,
                   const Eigen::VectorXd& weights, const CellDistanceOptions& options)
    : body_(body), options_(options) {
  check_3d(body, "body");
  options_.validate();
  if (points.cols() != 3 || points.rows() == 0 || weights.size() != points.rows())
    throw InvalidArgument(
        "quadrature cells: the scan's surface needs M > 0 points in 3D and M "
        "surface weights");
  if (!(weights.minCoeff() >= 0.0 && weights.sum() > 0.0))
    throw InvalidArgument(
        "quadrature cells: the scan's surface weights must be ≥ 0 with a "
        "positive sum");
  body_cells_ = fe::hex_decomposition(body);
  const std::vector<Eigen::Index> order = by_place(points);
  scan_points_.resize(points.rows(), 3);
  scan_weights_.resize(points.rows());
  for (std::size_t k = 0; k < order.size(); ++k) {
    scan_points_.row(static_cast<Eigen::Index>(k)) = points.row(order[k]);
    scan_weights_[static_cast<Eigen::Index>(k)] = weights[order[k]];
  }
}

CellForm::CellForm(const fe::Mesh& body, const fe::Mesh& target, const CellDistanceOptions& options)
    : body_(body), options_(options) {
  check_3d(body, "body");
  check_3d(target, "target's mesh");
  options_.validate();
  body_cells_ = fe::hex_decomposition(body);
  target_ = hex_cells(fe::hex_decomposition(target), target.nodes);
  const TriangleSurface surface = hex_boundary(target_);
  target_j_ = std::make_unique<BodyIntegral>(surface, body_integral_options(options_));
  target_sd_ = std::make_unique<SurfaceDistance>(surface);
  target_volume_ = enclosed_volume(surface);
}

CellForm::~CellForm() = default;

// The body at X + u: its hexahedra, boundary (with each surface point's node), J and signed
// distance, built once per evaluation.
struct CellForm::Deformed {
  HexCells x;
  std::vector<int> node;
  TriangleSurface surface;
  std::unique_ptr<BodyIntegral> j;
  std::unique_ptr<SurfaceDistance> sd;
};

CellForm::Deformed CellForm::deformed(const Eigen::VectorXd& u) const {
  const Eigen::Index n = body_.num_nodes();
  if (u.size() != 3 * n)
    throw InvalidArgument("CellForm: u has " + std::to_string(u.size()) + " values, expected " +
                          std::to_string(3 * n));
  Deformed d;
  d.x = hex_cells(body_cells_, body_.nodes + u.reshaped(3, n).transpose());
  d.surface = hex_boundary(d.x, &d.node);
  d.j = std::make_unique<BodyIntegral>(d.surface, body_integral_options(options_));
  if (!surface()) d.sd = std::make_unique<SurfaceDistance>(d.surface);  // the outer rule's
  return d;
}

/// ρ̃ = ((A² + B²)/2)^(1/2) from A^4 (the target's cells against the body) and B^4 (the body's
/// cells against the target); ∂ρ̃/∂A^4 = 1/(8 ρ̃ √(A^4)), likewise B. The body's points get
/// B's outer gradient and A's source bars (through the body's J, sd and |Ω_X|).
CellRho CellForm::rho(const Deformed& d, Eigen::VectorXd* grad) const {
  if (surface()) return scan_rho(d, scan_points_, grad);
  CellRho r;
  OuterMeanGradient ga, gb;
  r.a = directed_outer_mean(target_, *d.j, *d.sd, enclosed_volume(d.surface), options_,
                            grad ? &ga : nullptr);
  r.b = directed_outer_mean(d.x, *target_j_, *target_sd_, target_volume_, options_,
                            grad ? &gb : nullptr);
  double ca = 0.0, cb = 0.0;
  combine_means(&r, &ca, &cb);
  if (!grad) return r;
  Eigen::MatrixXd points = cb * gb.outer;  // ∂ρ̃/∂(the body's hexahedron points)
  add_source_bars(ga, ca, d.surface, d.node, &points);
  const Eigen::MatrixXd nodes = body_cells_.map.transpose() * points;  // mapᵀ: N by 3
  *grad = nodes.transpose().reshaped();                                // node-major
  return r;
}

/// Against a scan's surface: ρ̃ = A = (A^4)^(1/4), ∂ρ̃/∂A^4 = 1/(4 A³); the body's points get
/// A's source bars (through its J and |Ω_X|).
CellRho CellForm::scan_rho(const Deformed& d, const Eigen::MatrixXd& scan,
                           Eigen::VectorXd* grad) const {
  CellRho r;
  OuterMeanGradient ga;
  r.a = directed_point_mean(scan, scan_weights_, *d.j, enclosed_volume(d.surface), options_.epsilon,
                            grad ? &ga : nullptr);
  r.rho = std::sqrt(std::sqrt(r.a.mean));
  if (!grad) return r;
  Eigen::MatrixXd points = Eigen::MatrixXd::Zero(d.x.nodes.rows(), 3);
  add_source_bars(ga, 1.0 / (4.0 * r.rho * r.rho * r.rho), d.surface, d.node, &points);
  const Eigen::MatrixXd nodes = body_cells_.map.transpose() * points;  // mapᵀ: N by 3
  *grad = nodes.transpose().reshaped();                                // node-major
  return r;
}

CellRho CellForm::evaluate(const Eigen::VectorXd& u, Eigen::VectorXd* grad) const {
  return rho(deformed(u), grad);
}

std::shared_ptr<const CellForm::Deformed> CellForm::deform(const Eigen::VectorXd& u) const {
  return std::make_shared<const Deformed>(deformed(u));
}

Eigen::MatrixXd CellForm::pulled(const scan::Pose& Q) const {
  if (!surface())
    throw InvalidArgument(
        "pose: quadrature cells moves the body by a pose against a scan's "
        "surface only (scan_to_body)");
  if (!Q.rigid()) throw InvalidArgument("pose: quadrature cells needs a rigid pose (scale 1)");
  return scan::apply_points(Q.inverse(), scan_points_);
}

double CellForm::posed_rho(const Deformed& d, const scan::Pose& Q, const Eigen::Vector3d& centre,
                           Eigen::VectorXd* twist) const {
  const Eigen::MatrixXd z = pulled(Q);
  Eigen::MatrixXd g;  // ∂A^4/∂z_j
  const OuterMean a = directed_point_mean_moving(z, scan_weights_, *d.j, enclosed_volume(d.surface),
                                                 options_.epsilon, twist ? &g : nullptr);
  const double rho = std::sqrt(std::sqrt(a.mean));
  if (!twist) return rho;
  // k_j = R ∂ρ̃/∂z_j (rows: ∂ρ̃/∂z_jᵀ Rᵀ), ∂ρ̃/∂A^4 = 1/(4 ρ̃³); the scan's points seen as moving
  // by −k_j: PoseMap's twist gradient at δ = 0 about the centre.
  const Eigen::MatrixXd k = (g * Q.R.transpose()) / (4.0 * rho * rho * rho);
  *twist = scan::PoseMap(Q, centre, scan::PoseKind::rigid)
               .twist_gradient(scan_points_, -k, Eigen::VectorXd());
  return rho;
}

CellRho CellForm::evaluate(const Eigen::VectorXd& u, const scan::Pose& Q,
                           Eigen::VectorXd* grad) const {
  const Eigen::MatrixXd z = pulled(Q);
  return scan_rho(deformed(u), z, grad);
}

CellForm::Fields CellForm::fields(const Eigen::VectorXd& u, const Eigen::MatrixXd& moving,
                                  const Eigen::MatrixXd& target_points) const {
  const Deformed d = deformed(u);
  Fields f;
  f.rho = rho(d, nullptr);
  if (!surface()) f.moving = d_tilde(*target_j_, target_volume_, options_.epsilon, moving);
  f.target = d_tilde(*d.j, enclosed_volume(d.surface), options_.epsilon, target_points);
  return f;
}

// The target against itself: both directed means are the same one, A^4 over its cells against
// its own J, sd and |Ω| (built once), so ρ̃ = ((A² + A²)/2)^(1/2) = (A^4)^(1/4).
double CellForm::self_rho() const {
  if (surface())
    throw InvalidArgument("quadrature cells: a scan's surface has no cells, hence no self floor");
  const double a4 =
      directed_outer_mean(target_, *target_j_, *target_sd_, target_volume_, options_).mean;
  return std::sqrt(std::sqrt(a4));
}

}  // namespace softhd::detail

#include "tracking_bench.hpp"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <optional>
#include <random>
#include <sstream>

#include "softhd/control/scene_target.hpp"
#include "softhd/error.hpp"
#include "softhd/samplers.hpp"

namespace softhd::bench {

softhd::Scene scene_file(const std::string& name) {
  return softhd::load_scene(std::string(SOFTHD_SOURCE_DIR) + "/data/scenes/" + name + ".json");
}

Body make_body(softhd::Scene scene, const Eigen::Vector3i& cells, const Eigen::Vector3d& shift) {
  if (cells.minCoeff() > 0) scene.body.cells = cells.head(scene.body.dim());
  scene.body.lower += shift.head(scene.body.dim());
  scene.body.upper += shift.head(scene.body.dim());
  Body b;
  b.scene = std::move(scene);
  b.assembler = std::make_unique<fe::Assembler>(b.scene.body.make_assembler());
  b.space = std::make_unique<fe::ControlSpace>(b.scene.body.make_control_space(*b.assembler));
  return b;
}

ArcMap arc_of(const softhd::Scene& scene, double angle) { return arc_map(scene, angle); }

Eigen::VectorXd arc_displacement(const ArcMap& T, const fe::Mesh& mesh,
                                 const Eigen::Vector3d& shift) {
  Eigen::VectorXd u(mesh.num_nodes() * 3);
  for (Eigen::Index n = 0; n < mesh.num_nodes(); ++n) {
    const Eigen::Vector3d X = mesh.nodes.row(n).transpose();
    u.segment<3>(3 * n) = T(X - shift) + shift - X;  // u_T = T(X − s) + s − X
  }
  return u;
}

PointCloud shifted(const PointCloud& cloud, const Eigen::Vector3d& shift) {
  Eigen::MatrixXd p = cloud.points();
  p.rowwise() += shift.head(cloud.dim()).transpose();
  return PointCloud(p, cloud.volumes());
}

namespace {

Eigen::VectorXd box_lower(const softhd::Scene& s) {
  return s.body.lower - s.body.lower;
}  // plate at origin
Eigen::VectorXd box_upper(const softhd::Scene& s) { return s.body.upper - s.body.lower; }

// t ∈ [0, 1) with density (1 + c t)/(1 + c/2), c = 4: the inverse of its CDF at u.
double nonuniform_t(double u) {
  const double c = 4.0;
  return (-1.0 + std::sqrt(1.0 + 2.0 * c * u * (1.0 + 0.5 * c))) / c;
}
double nonuniform_density(double t) { return (1.0 + 4.0 * t) / 3.0; }

double uniform01(std::mt19937_64& g) { return static_cast<double>(g() >> 11) * 0x1.0p-53; }

}  // namespace

PointCloud arc_grid(const softhd::Scene& box, const ArcMap& T, const Eigen::Vector3i& counts) {
  return T.apply(sample_box_grid(box_lower(box), box_upper(box), counts));
}

PointCloud arc_random(const softhd::Scene& box, const ArcMap& T, int n, std::uint64_t seed) {
  return T.apply(sample_uniform_random(box_lower(box), box_upper(box), n, seed));
}

PointCloud arc_nonuniform(const softhd::Scene& box, const ArcMap& T, int n, std::uint64_t seed) {
  const Eigen::Vector3d hi = box_upper(box);
  std::mt19937_64 g(seed);
  Eigen::MatrixXd p(n, 3);
  Eigen::VectorXd v(n);
  const double volume = hi.prod();
  for (int i = 0; i < n; ++i) {
    const double t = nonuniform_t(uniform01(g));
    p.row(i) << t * hi[0], uniform01(g) * hi[1], uniform01(g) * hi[2];
    v[i] = volume / (n * nonuniform_density(t));  // V_i = |Ω| / (n p(X_i))
  }
  return T.apply(PointCloud(p, v));
}

PointCloud jittered(const PointCloud& cloud, double sigma, std::uint64_t seed) {
  std::mt19937_64 g(seed);
  std::normal_distribution<double> noise(0.0, sigma);
  Eigen::MatrixXd p = cloud.points();
  for (Eigen::Index i = 0; i < p.rows(); ++i)
    for (Eigen::Index k = 0; k < p.cols(); ++k) p(i, k) += noise(g);
  return PointCloud(p, cloud.volumes());
}

PointCloud arc_surface(const softhd::Scene& box, const ArcMap& T, double spacing, int random_n,
                       std::uint64_t seed) {
  const Eigen::Vector3d hi = box_upper(box);
  std::vector<Eigen::Vector3d> pts;
  std::vector<double> area;
  std::mt19937_64 g(seed);
  // Face k = axis normal to it, side s ∈ {0, 1}; the two tangent axes a, b.
  double total_area = 0.0;
  for (int k = 0; k < 3; ++k) total_area += 2.0 * hi.prod() / hi[k];
  for (int k = 0; k < 3; ++k) {
    const int a = (k + 1) % 3, b = (k + 2) % 3;
    const double face = hi[a] * hi[b];
    for (int side = 0; side < 2; ++side) {
      if (random_n > 0) {
        // Points per face ∝ its area; X1 along a face drawn with density ∝ 1 + 4 X1/L.
        const int n = std::max(1, static_cast<int>(std::lround(random_n * face / total_area)));
        for (int i = 0; i < n; ++i) {
          Eigen::Vector3d X;
          X[k] = side * hi[k];
          double w = face / n;
          for (int axis : {a, b}) {
            if (axis == 0) {
              const double t = nonuniform_t(uniform01(g));
              X[0] = t * hi[0];
              w /= nonuniform_density(t);
            } else {
              X[axis] = uniform01(g) * hi[axis];
            }
          }
          pts.push_back(X);
          area.push_back(w);
        }
      } else {
        const int na = std::max(1, static_cast<int>(std::lround(hi[a] / spacing)));
        const int nb = std::max(1, static_cast<int>(std::lround(hi[b] / spacing)));
        for (int i = 0; i < na; ++i)
          for (int j = 0; j < nb; ++j) {
            Eigen::Vector3d X;
            X[k] = side * hi[k];
            X[a] = (i + 0.5) * hi[a] / na;
            X[b] = (j + 0.5) * hi[b] / nb;
            pts.push_back(X);
            area.push_back(face / (na * nb));
          }
      }
    }
  }
  Eigen::MatrixXd p(pts.size(), 3);
  Eigen::VectorXd v(pts.size());
  for (size_t i = 0; i < pts.size(); ++i) {
    p.row(i) = pts[i].transpose();
    v[i] = area[i];
  }
  return T.apply(PointCloud(p, v));
}

RunSettings::RunSettings() {
  run.optimiser.max_iterations = 60;
  run.distance.method = Method::exact;
  run.distance.tolerance = 1e-6;
}

bool Run::finite() const {
  const ShapeTrackingSummary& s = summary;
  bool ok = std::isfinite(s.rho_start) && s.floor().has_value() && std::isfinite(s.rho_final) &&
            std::isfinite(s.J_final) && std::isfinite(s.seconds) && s.control.allFinite() &&
            s.displacement.allFinite();
  if (s.floor_self) ok = ok && std::isfinite(*s.floor_self);
  if (s.floor_matched) ok = ok && std::isfinite(*s.floor_matched);
  if (s.shape_error_max) ok = ok && std::isfinite(*s.shape_error_max);
  for (const TrackingIteration& it : s.history)
    ok = ok && std::isfinite(it.J) && std::isfinite(it.projected_gradient_norm);
  return ok;
}

Run run_tracking(std::vector<std::pair<std::string, std::string>> params, Body& body,
                 const PointCloud& target, const std::optional<Eigen::VectorXd>& map,
                 const RunSettings& settings) {
  Run run;
  run.params = std::move(params);
  run.nodes = body.mesh().num_nodes();
  run.controls = body.space->size();
  run.target_points = target.size();
  std::string label;
  for (const auto& [k, v] : run.params) label += k + "=" + v + " ";
  try {
    TrackingRunCallbacks cb;
    if (settings.progress)
      cb.on_iteration = [&](const TrackingIteration& it, const Eigen::VectorXd&) {
        if (it.iteration % 10 == 0)
          std::fprintf(stderr, "    %s it %d rho/floor %.4g  %.0f s\n", label.c_str(), it.iteration,
                       it.rho_over_floor, it.seconds);
      };
    TrackingRun tracking(body.scene, *body.assembler, *body.space,
                         SceneTarget{target, map, "the benchmark's target", {}}, settings.run);
    run.summary = tracking.run(cb);
  } catch (const std::exception& e) {
    run.error = e.what();
    run.summary.termination = std::string("error: ") + e.what();
  }
  if (settings.progress) {
    const ShapeTrackingSummary& s = run.summary;
    std::fprintf(stderr, "  %s: rho %.4g -> %.4g (%.3g x floor), %d it, %.1f s, %s\n",
                 label.c_str(), s.rho_start, s.rho_final,
                 s.rho_final / s.floor().value_or(std::nan("")), s.iterations, s.seconds,
                 s.termination.c_str());
  }
  return run;
}

std::string fmt(double v, int precision) {
  std::ostringstream s;
  s.precision(precision);
  s << v;
  return s.str();
}

namespace {

std::string csv_quote(const std::string& s) {
  std::string out = "\"";
  for (char c : s) out += (c == '"') ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

std::string opt(const std::optional<double>& v) { return v ? fmt(*v, 10) : ""; }

}  // namespace

void write_csv(const std::string& path, const std::vector<Run>& runs) {
  std::ofstream out(path);
  if (!out) throw FileError("cannot write " + path);
  if (runs.empty()) return;
  for (const auto& [k, v] : runs.front().params) out << k << ',';
  out << "nodes,controls,target_points,floor_self,floor_matched,rho_start,rho_final,"
         "rho_over_floor,shape_error_max,shape_error_rms,iterations,evaluations,"
         "failed_evaluations,newton_iterations,seconds,seconds_state,seconds_distance,"
         "seconds_adjoint,seconds_optimizer,seconds_per_iteration,it_2,t_2,it_1.5,t_1.5,"
         "it_1.25,t_1.25,finite,converged,termination\n";
  for (const Run& r : runs) {
    const ShapeTrackingSummary& s = r.summary;
    for (const auto& kv : r.params) out << csv_quote(kv.second) << ',';
    out << r.nodes << ',' << r.controls << ',' << r.target_points << ',' << opt(s.floor_self) << ','
        << opt(s.floor_matched) << ',' << fmt(s.rho_start, 10) << ',' << fmt(s.rho_final, 10) << ','
        << fmt(s.rho_final / s.floor().value_or(std::nan("")), 6) << ',' << opt(s.shape_error_max)
        << ',' << opt(s.shape_error_rms) << ',' << s.iterations << ',' << s.evaluations << ','
        << s.failed_evaluations << ',' << s.newton_iterations << ',' << fmt(s.seconds, 6) << ','
        << fmt(s.seconds_state, 6) << ',' << fmt(s.seconds_distance, 6) << ','
        << fmt(s.seconds_adjoint, 6) << ',' << fmt(s.seconds_optimizer, 6) << ','
        << fmt(s.iterations > 0 ? s.seconds / s.iterations : 0.0, 6);
    for (double k : {2.0, 1.5, 1.25}) {
      const auto hit = first_below(s.history, k);
      out << ',' << (hit ? std::to_string(hit->iteration) : "") << ','
          << (hit ? fmt(hit->seconds, 6) : "");
    }
    out << ',' << (r.error.empty() && r.finite() ? 1 : 0) << ',' << (s.converged() ? 1 : 0) << ','
        << csv_quote(s.termination) << '\n';
  }
  if (!out) throw FileError("error while writing " + path);
}

std::string option(int argc, char** argv, const std::string& name, const std::string& fallback) {
  for (int i = 1; i + 1 < argc; ++i)
    if (argv[i] == name) return argv[i + 1];
  return fallback;
}

bool has_flag(int argc, char** argv, const std::string& name) {
  for (int i = 1; i < argc; ++i)
    if (argv[i] == name) return true;
  return false;
}

}  // namespace softhd::bench

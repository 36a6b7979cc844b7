#include "run_files.hpp"

#include <cmath>
#include <cstdio>
#include <optional>
#include <sstream>

#include "softhd/fe/output.hpp"
#include "softhd/io/atomic_file.hpp"
#include "softhd/io/cloud_io.hpp"
#include "softhd/io/vtu.hpp"

namespace softhd::detail {

namespace fs = std::filesystem;

namespace {

const char* kHistoryHeader =
    "iteration,evaluation,J,rho,A,B,rho_over_floor,projected_gradient_norm,newton_iterations,"
    "factorizations,seconds_state,seconds_distance,seconds_adjoint,seconds,level";

// With the optimiser newton (an objective with the Hessian-vector product): its step.
const char* kNewtonHeader = ",cg_iterations,hessian_products,trust_radius";

// With a pose: the twist of the best pose so far (ω, t, log s of P, scan → body).
const char* kPoseHeader = ",pose_w1,pose_w2,pose_w3,pose_t1,pose_t2,pose_t3,pose_log_s";

nlohmann::json optional_json(const std::optional<double>& v) {
  return v ? nlohmann::json(*v) : nlohmann::json(nullptr);
}

std::string body_name(int iteration) {
  char name[32];
  std::snprintf(name, sizeof name, "body_%04d.vtu", iteration);
  return name;
}

// summary.json's entries about the end of the run.
void add_final(const ShapeTrackingSummary& s, nlohmann::json& sum) {
  sum["floor_self"] = optional_json(s.floor_self);  // with a known map, made at the end
  sum["floor_matched"] = optional_json(s.floor_matched);
  sum["rho_final"] = s.rho_final;
  sum["J_final"] = s.J_final;
  sum["rho_final_over_floor"] =
      optional_json(s.floor() ? std::optional<double>(s.rho_final / *s.floor()) : std::nullopt);
  sum["iterations"] = s.iterations;
  sum["evaluations"] = s.evaluations;
  sum["replayed_evaluations"] = s.replayed_evaluations;
  sum["failed_evaluations"] = s.failed_evaluations;
  sum["termination"] = s.termination;
  sum["converged"] = s.converged();
  sum["shape_error_max"] = optional_json(s.shape_error_max);
  sum["shape_error_rms"] = optional_json(s.shape_error_rms);
  sum["seconds"] = s.seconds;
  sum["newton_iterations"] = s.newton_iterations;
  sum["factorizations"] = s.factorizations;
  sum["seconds_state"] = s.seconds_state;
  sum["seconds_distance"] = s.seconds_distance;
  sum["seconds_adjoint"] = s.seconds_adjoint;
  sum["seconds_optimizer"] = s.seconds_optimizer;
  if (s.pose)
    sum["pose"] = {{"matrix", matrix_json(s.pose->matrix())},
                   {"twist", matrix_json(s.pose->twist())},
                   {"xi", matrix_json(s.pose_twist)}};
}

}  // namespace

nlohmann::json matrix_json(const Eigen::MatrixXd& m) {
  nlohmann::json j = nlohmann::json::array();
  if (m.cols() == 1) {
    for (Eigen::Index i = 0; i < m.rows(); ++i) j.push_back(m(i, 0));
    return j;
  }
  for (Eigen::Index i = 0; i < m.rows(); ++i) {
    nlohmann::json row = nlohmann::json::array();
    for (Eigen::Index c = 0; c < m.cols(); ++c) row.push_back(m(i, c));
    j.push_back(row);
  }
  return j;
}

std::string history_row(const TrackingIteration& it, bool newton) {
  std::vector<double> v{double(it.iteration),
                        double(it.evaluation),
                        it.J,
                        it.rho,
                        it.A,
                        it.B,
                        it.rho_over_floor,
                        it.projected_gradient_norm,
                        double(it.newton_iterations),
                        double(it.factorizations),
                        it.seconds_state,
                        it.seconds_distance,
                        it.seconds_adjoint,
                        it.seconds,
                        double(it.level)};
  if (newton)
    v.insert(v.end(), {double(it.cg_iterations), double(it.hessian_products), it.trust_radius});
  for (Eigen::Index k = 0; k < it.pose.size(); ++k) v.push_back(it.pose[k]);
  std::ostringstream s;
  s.precision(10);
  for (size_t k = 0; k < v.size(); ++k) {
    if (k) s << ',';
    if (std::isfinite(v[k])) s << v[k];  // a ratio without a floor stays empty
  }
  return s.str();
}

RunFiles::RunFiles(fs::path dir, const ShapeObjective& objective, const fe::ControlSpace& space,
                   long vtu_every, bool writes, nlohmann::json summary)
    : dir_(std::move(dir)),
      objective_(objective),
      space_(space),
      vtu_every_(vtu_every),
      writes_(writes),
      summary_(std::move(summary)) {}

void RunFiles::begin(bool resume) {
  // From here on the folder always holds history.csv and summary.json; a resumed run keeps
  // the earlier process's until it has new rows.
  summary_["status"] = "interrupted";  // until the run ends: a killed run leaves this
  if (!resume || !fs::exists(dir_ / "history.csv")) write_history();
  if (!resume || !fs::exists(dir_ / "summary.json")) write_summary(summary_);
}

void RunFiles::start(const ShapeTrackingSummary& start, const Eigen::VectorXd& m0,
                     const Eigen::VectorXd& u0) {
  summary_["rho_start"] = start.rho_start;
  summary_["floor_self"] = optional_json(start.floor_self);
  summary_["floor_matched"] = optional_json(start.floor_matched);
  write_body(0, m0, u0);
}

void RunFiles::iteration(const TrackingIteration& it, const Eigen::VectorXd& m,
                         const Eigen::VectorXd& u) {
  rows_.push_back(history_row(it, objective_.options().second_order));
  // A replayed iteration's VTU was written by the process that made it.
  if (vtu_every_ > 0 && it.iteration % vtu_every_ == 0) {
    if (it.replayed)
      list_body(it.iteration);
    else
      write_body(it.iteration, m, u);
  }
  if (it.replayed) return;
  write_history();
  nlohmann::json now = summary_;
  now["iterations"] = it.iteration;
  now["evaluations"] = it.evaluation;
  now["J"] = it.J;
  now["rho"] = it.rho;
  now["seconds"] = it.seconds;
  write_summary(now);
}

void RunFiles::level_iteration(const TrackingIteration& it) {
  rows_.push_back(history_row(it, objective_.options().second_order));
  if (!it.replayed) write_history();
}

void RunFiles::finish(const ShapeTrackingSummary& s, const PointCloud& target) {
  const HausdorffResult fields = write_body(s.iterations, s.control, s.displacement, s.pose_twist);
  if (!writes_) return;
  write_vtu_cloud((dir_ / "target.vtu").string(), target, {{"d_tilde", fields.field_target}});
  write_ply_cloud((dir_ / "target.ply").string(), target);
  // A camera-frame target moved into the body's frame by the final pose.
  if (s.pose) write_ply_cloud((dir_ / "target_aligned.ply").string(), s.pose->apply(target, true));
  write_ply_cloud((dir_ / "body_final.ply").string(), objective_.moving_cloud().at(s.displacement));
  write_history();
  const fe::Mesh& mesh = objective_.assembler().mesh();
  fe::write_control_file((dir_ / "control.csv").string(), space_.positions(mesh), s.control);
  summary_["status"] = "finished";
  add_final(s, summary_);
  write_summary(summary_);
}

HausdorffResult RunFiles::write_body(int iteration, const Eigen::VectorXd& m,
                                     const Eigen::VectorXd& u, const Eigen::VectorXd& xi) {
  const fe::Assembler& a = objective_.assembler();
  const HausdorffResult r = objective_.fields(u, xi);
  if (!writes_) return r;
  std::vector<VtuField> point{{"m", fe::control_at_nodes(a.mesh(), space_, m)}};
  std::vector<VtuField> cell;
  if (objective_.options().particles == Particles::nodes)
    point.push_back({"d_tilde", r.field_moving});
  cell.push_back({"J", a.jacobians(u).rowwise().mean()});
  if (space_.kind() == fe::ControlKind::kElement) cell.push_back({"m", m});
  fe::write_vtu_mesh((dir_ / body_name(iteration)).string(), a.mesh(), u, point, cell);
  list_body(iteration);
  return r;
}

void RunFiles::list_body(int iteration) {
  if (!writes_) return;
  if (!pvd_.empty() && pvd_.back().second == body_name(iteration)) return;
  if (!fs::exists(dir_ / body_name(iteration))) return;
  pvd_.emplace_back(iteration, body_name(iteration));
  write_pvd((dir_ / "body.pvd").string(), pvd_);
}

void RunFiles::write_history() const {
  if (!writes_) return;
  std::ostringstream h;
  h << kHistoryHeader << (objective_.options().second_order ? kNewtonHeader : "")
    << (objective_.pose() ? kPoseHeader : "") << '\n';
  for (const std::string& r : rows_) h << r << '\n';
  write_file_atomically((dir_ / "history.csv").string(), h.str());
}

void RunFiles::write_summary(const nlohmann::json& sum) const {
  if (!writes_) return;
  write_file_atomically((dir_ / "summary.json").string(), sum.dump(2) + "\n");
}

}  // namespace softhd::detail

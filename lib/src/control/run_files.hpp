#pragma once
// The files of a tracking run in its folder (tracking_run.hpp): history.csv and summary.json
// (status "interrupted" until the end) rewritten as the run goes, body VTUs with their PVD, and
// at the end the clouds and control.csv. Every file is written atomically (io/atomic_file.hpp).

#include <Eigen/Core>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "softhd/control/shape_objective.hpp"
#include "softhd/control/shape_tracking.hpp"
#include "softhd/control/tracking_run.hpp"
#include "softhd/fe/control.hpp"

namespace softhd::detail {

/// history.csv's row of an iteration: its numbers with 10 significant digits (%.10g), a ratio
/// without a floor left empty; with `newton`, its CG iterations, Hessian-vector products and
/// trust radius after them.
std::string history_row(const TrackingIteration& it, bool newton = false);
/// A matrix as JSON: rows of numbers (a vector: a flat list).
nlohmann::json matrix_json(const Eigen::MatrixXd& m);

class RunFiles {
 public:
  /// `writes` false: the fields are computed (collective with a shared distance) but no file
  /// is written (ranks other than 0). `summary` holds the run's setup entries.
  RunFiles(std::filesystem::path dir, const ShapeObjective& objective,
           const fe::ControlSpace& space, long vtu_every, bool writes, nlohmann::json summary);

  /// Before the first solve: history.csv (header only) and summary.json (status
  /// "interrupted"), except that a resumed run keeps the earlier process's.
  void begin(bool resume);
  /// After the start solve: the floors, and body_0000.vtu at the start control m0.
  void start(const ShapeTrackingSummary& start, const Eigen::VectorXd& m0,
             const Eigen::VectorXd& u0);
  /// After an accepted iteration (u: the state of the best control m, unless replayed).
  void iteration(const TrackingIteration& it, const Eigen::VectorXd& m, const Eigen::VectorXd& u);
  /// After an accepted iteration of a coarse level (TrackingRunOptions::Levels): its row.
  void level_iteration(const TrackingIteration& it);
  /// summary.json's entries of the set-up and the end (e.g. the levels), kept from now on.
  nlohmann::json& summary() { return summary_; }
  /// At the end: the final body and clouds (with a pose also target_aligned.ply, the target
  /// moved by it), history.csv, control.csv and summary.json.
  void finish(const ShapeTrackingSummary& s, const PointCloud& target);

 private:
  /// The body's VTU; its fields at the pose twist xi (empty: the start pose).
  HausdorffResult write_body(int iteration, const Eigen::VectorXd& m, const Eigen::VectorXd& u,
                             const Eigen::VectorXd& xi = Eigen::VectorXd());
  void list_body(int iteration);
  void write_history() const;
  void write_summary(const nlohmann::json& sum) const;

  std::filesystem::path dir_;
  const ShapeObjective& objective_;
  const fe::ControlSpace& space_;
  long vtu_every_;
  bool writes_;
  nlohmann::json summary_;
  std::vector<std::string> rows_;
  std::vector<std::pair<double, std::string>> pvd_;
};

}  // namespace softhd::detail

#pragma once
// The coarse levels of a multilevel tracking run (TrackingRunOptions::Levels,
// docs/formulation.md §4.8): each level's body, control space, target and objective, and the
// prolongation of a level's control to the next finer one.

#include <Eigen/Core>
#include <memory>
#include <optional>
#include <vector>

#include "softhd/control/scene.hpp"
#include "softhd/control/scene_target.hpp"
#include "softhd/control/shape_objective.hpp"
#include "softhd/control/tracking_run.hpp"
#include "softhd/fe/assembly.hpp"
#include "softhd/fe/control.hpp"
#include "softhd/point_cloud.hpp"

namespace softhd::detail {

/// One coarse level: the scene with its box halved `level` times, its body and its target.
struct CoarseProblem {
  int level = 0;
  Scene scene;
  std::unique_ptr<fe::Assembler> assembler;
  std::unique_ptr<fe::ControlSpace> control;
  std::optional<fe::Assembler> two_level;  ///< this level's own two-level starts, if any
  std::optional<SceneTarget> target;       ///< set when built (no empty cloud)
  std::unique_ptr<ShapeObjective> objective;
};

/// β of the run against `target`: options.distance.beta_for the sides of the run's form
/// (options.distance.form's, else the target block's; visible with the target's camera).
double run_beta(const TrackingRunOptions& options, const SceneTarget& target);

/// Sets the objective's distance form from the target block's (target_form; nothing for the
/// default symmetric form without a cap) and appends it to the target's description.
void apply_target_form(ShapeObjective& objective, SceneTarget& target);

/// Every `stride`-th point of `cloud` (from the first), the volumes scaled so that their total
/// is the cloud's.
PointCloud subsampled(const PointCloud& cloud, int stride);

/// The options.levels − 1 coarse levels of `scene`, coarsest first, against coarse versions
/// of `target` (the target of the user's mesh). Throws InvalidArgument naming `levels` if the
/// body has fewer coarser levels (fe::coarsened), and as scene_target.
std::vector<std::unique_ptr<CoarseProblem>> coarse_problems(const Scene& scene,
                                                            const SceneTarget& target,
                                                            const TrackingRunOptions& options);

}  // namespace softhd::detail

#include "multilevel.hpp"

#include <algorithm>
#include <sstream>
#include <string>

#include "softhd/error.hpp"
#include "softhd/fe/grid_sequencing.hpp"
#include "softhd/fe/interpolation.hpp"
#include "softhd/fe/state_equation.hpp"

namespace softhd::detail {

PointCloud subsampled(const PointCloud& cloud, int stride) {
  if (stride < 1) throw InvalidArgument("subsampled: stride must be >= 1");
  const Eigen::Index n = (static_cast<Eigen::Index>(cloud.size()) + stride - 1) / stride;
  Eigen::MatrixXd points(n, cloud.dim());
  Eigen::VectorXd volumes(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    points.row(i) = cloud.points().row(i * stride);
    volumes[i] = cloud.volumes()[i * stride];
  }
  // Σ v kept: v_i ← v_i · (Σ_all v) / (Σ_kept v).
  volumes *= cloud.volumes().sum() / volumes.sum();
  return PointCloud(std::move(points), std::move(volumes));
}

namespace {

// The target of a coarse level: the scene's for its body (an arc grid follows the mesh), or
// the finer level's target subsampled where that gives no fewer points.
SceneTarget coarse_target(const Scene& coarse, const fe::Mesh& mesh, const SceneTarget& finer,
                          const TrackingRunOptions& options) {
  SceneTarget t = tracking_target(coarse, mesh, options);
  if (t.cloud.size() >= finer.cloud.size()) {
    const int stride = 1 << coarse.body.dim();  // 2^d: as a grid halved along every axis
    t.cloud = subsampled(finer.cloud, stride);
    t.description = finer.description + ", every " + std::to_string(stride) + "th point";
  }
  return t;
}

// The body and the levels − 1 coarser levels of multilevel optimisation (Halving::rounded).
fe::MeshHierarchy level_hierarchy(const fe::Body& body, int levels) {
  try {
    return fe::MeshHierarchy(body, fe::Halving::rounded, levels - 1);
  } catch (const InvalidArgument& e) {
    throw InvalidArgument("levels.count: " + std::to_string(levels) + ": " + e.what());
  }
}

}  // namespace

double run_beta(const TrackingRunOptions& options, const SceneTarget& target) {
  // The sides the run's form will have: the options' form replaces the target block's, and
  // the target's camera makes it visible (apply_target_settings; a conflict is set_form's).
  const Sides sides = target.camera           ? Sides::visible
                      : options.distance.form ? options.distance.form->sides
                                              : target.distance.sides;
  return options.distance.beta_for(sides);
}

void apply_target_form(ShapeObjective& objective, SceneTarget& target) {
  const TargetDistance& d = target.distance;
  // Nothing to set for the plain form, unless a camera made the objective's visible (then a
  // symmetric form asked for is a conflict set_form names).
  if (d.sides == Sides::symmetric && d.cap == 0.0 && d.cap_factor == 0.0 &&
      !objective.options().camera)
    return;
  const DistanceForm form = target_form(d, objective);
  objective.set_form(form);
  std::ostringstream line;
  line.precision(6);
  line << ", distance " << to_string(form.sides);
  if (form.cap.c > 0.0) line << ", cap c = " << form.cap.c << " (q = " << form.cap.q << ")";
  target.description += line.str();
}

std::vector<std::unique_ptr<CoarseProblem>> coarse_problems(const Scene& scene,
                                                            const SceneTarget& target,
                                                            const TrackingRunOptions& options) {
  std::vector<std::unique_ptr<CoarseProblem>> levels;  // finest first while built
  TrackingRunOptions o = options;
  if (o.distance.method == Method::tree)
    o.distance.tolerance = std::max(options.distance.tolerance, options.levels.coarse_tolerance);
  ShapeObjectiveOptions so = o.objective();
  apply_target_settings(target, &so);  // the user's target's view on every level
  so.hausdorff.params.beta = run_beta(options, target);
  const fe::MeshHierarchy hierarchy = level_hierarchy(scene.body, options.levels.count);
  const SceneTarget* finer_target = &target;
  for (int level = 1; level < options.levels.count; ++level) {
    auto p = std::make_unique<CoarseProblem>();
    p->level = level;
    p->scene = scene;  // the name, source and target of the scene
    p->scene.body = hierarchy.level(level);
    p->assembler = std::make_unique<fe::Assembler>(p->scene.body.make_assembler());
    p->control =
        std::make_unique<fe::ControlSpace>(p->scene.body.make_control_space(*p->assembler));
    p->target.emplace(coarse_target(p->scene, p->assembler->mesh(), *finer_target, options));
    p->objective = std::make_unique<ShapeObjective>(
        *p->assembler, *p->control, HausdorffTarget(p->target->cloud, so.hausdorff), so,
        fe::state_solver_factory(p->scene.body, options.state.backend, p->assembler.get(),
                                 p->control.get()));
    if (options.distance.form) p->target->distance = *options.distance.form;
    apply_target_form(*p->objective, *p->target);
    if (options.state.coarse_levels == CoarseLevel::automatic &&
        fe::grid_levels(p->scene.body, fe::GridSequencingOptions{}) > 0) {
      p->two_level.emplace(
          fe::MeshHierarchy(p->scene.body, fe::Halving::nested, 1).level(1).make_assembler());
      p->objective->state_path().use_coarse_level(*p->two_level);
    }
    levels.push_back(std::move(p));
    finer_target = &*levels.back()->target;
  }
  std::reverse(levels.begin(), levels.end());
  return levels;
}

}  // namespace softhd::detail

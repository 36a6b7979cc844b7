#pragma once
/// \file tracking_run.hpp
/// One shape-tracking run as `softhd optimise`, the Python `softhd.optimise` and the benchmarks
/// make it (docs/guide.md §5, docs/formulation.md §4): the body and its control space from a
/// scene, the target (a cloud file, the scene's own "target", or a given cloud), the objective
/// and its options, the bounds and the start from the scene, two-level starts, and — with an
/// output folder — the checkpoint (its fingerprint, resume) and the run's files (history.csv,
/// summary.json, body VTUs, control.csv, the clouds). The front ends parse their arguments into
/// TrackingRunOptions and print from the callbacks; the defaults below are theirs.

#include <Eigen/Core>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "softhd/control/bounded_optimizer.hpp"
#include "softhd/control/scene_target.hpp"
#include "softhd/control/shape_objective.hpp"
#include "softhd/control/shape_tracking.hpp"
#include "softhd/fe/assembly.hpp"
#include "softhd/fe/control.hpp"
#include "softhd/fe/state_backend.hpp"
#include "softhd/hausdorff.hpp"
#include "softhd/work_share.hpp"

namespace softhd {

/// The coarse start of a run's state solves, its two-level starts (docs/formulation.md §4.7;
/// `--coarse-levels`, as `softhd forward`'s): a large control step is solved first on the
/// coarse level of fe::coarsened (a box with half the cells along the even axes, a mesh file
/// of order 2 as P1/Q1 on its vertices), at most one level.
enum class CoarseLevel {
  automatic,  ///< "auto": when that mesh exists and has >= 32 elements (fe::grid_levels)
  off,        ///< "0": every state solve on the user's mesh alone
};
/// "auto" or "0".
std::string to_string(CoarseLevel level);
/// The CoarseLevel named by to_string; throws InvalidArgument naming `state.coarse_levels`.
CoarseLevel coarse_level_from_string(const std::string& name);

/// β of the scan forms (Sides::scan_to_body, Sides::visible) in a tracking run whose β is
/// automatic (TrackingRunOptions::Distance::params.beta 0): 2. Measured on noisy depth views
/// of the bent finger with the pose known, it gave a node error 0.23–0.94 × that of the
/// paper's 4 on every view and noise level, 0–1 % of the body's size (docs/formulation.md
/// §8.11, "β against the noise").
inline constexpr double kScanFormBeta = 2.0;

/// Settings of one tracking run, grouped by concern. The defaults are those of
/// `softhd optimise` and of Python's `softhd.optimise` (written here only); the flag and the
/// keyword of each field are in tracking_run_fields() (softhd/control/run_fields.hpp).
struct TrackingRunOptions {
  /// The optimiser (BoundedOptimizerOptions) and its start.
  struct Optimiser {
    Algorithm algorithm = Algorithm::mma;  ///< mma
    /// newton: the Hessian-vector product's part (ShapeObjective::hessian_product): the exact
    /// reduced Hessian (full, the default) or its positive semi-definite Gauss–Newton part.
    HessianPart hessian = HessianPart::full;
    int max_iterations = 200;  ///< accepted iterations, over all resumes (200)
    int max_evaluations = 0;   ///< objective evaluations; 0 (default): 5 × max_iterations + 20
    double max_seconds = 0.0;  ///< wall-clock limit over all resumes; 0 (default): none
    double relative_change = 1e-6;  ///< stop when J changes by ≤ this relative, 3 times in a row
    /// Rounds of ≤ 10 evaluations move m by ≤ this × bound range; newton: the trust radius is
    /// ≤ this × the bound range, root-mean-square over the controls (0.1)
    double move_limit = 0.1;
    /// The starting control (one value per control, each within the scene's control bounds;
    /// TrackingRun refuses any other), e.g. an earlier run's: a staged run (docs/formulation.md
    /// §8.10). None (default): the scene's control.initial everywhere; an empty vector is
    /// refused. Single-level runs only (levels 1; the automatic levels are 1 then).
    std::optional<Eigen::VectorXd> initial_control;
  };
  /// The distance (ShapeObjectiveOptions::hausdorff): the moving cloud, the functional and its
  /// pair sums, and its form.
  struct Distance {
    Particles particles = Particles::nodes;                ///< nodes
    ParticleVolumes volumes = ParticleVolumes::reference;  ///< reference
    /// α, β, γ, ε (4, 0, 2, 1e-3). β 0 (the default) is automatic (beta_for): the paper's 4
    /// for the symmetric distance, kScanFormBeta (2) for scan_to_body and visible; any other
    /// β is used for every form.
    HausdorffParams params{4.0, 0.0, 2.0, 1e-3};
    /// The pair sums (tree, the default): the tree sums exactly wherever its far field would
    /// not be cheaper.
    Method method = Method::tree;
    /// The tree's relative error bound on every kernel sum (1e-2: it ends the bending and
    /// torsion runs at the exact method's ρ̃/floor, docs/guide.md §5).
    double tolerance = 1e-2;
    /// The distance's form (docs/formulation.md §8), replacing the target's own as a whole (a
    /// scene's "distance", "cap", "cap_q"; a file or array target has the symmetric form
    /// without a cap). Unset (default): the target's. Sides::visible is refused (it needs the
    /// camera).
    std::optional<TargetDistance> form;
    /// Where the distance is integrated (docs/formulation.md §2.8): collocation (at the clouds'
    /// points) or cells (over the body's cells and the target's: an arc, or a solved_on cloud;
    /// a target without cells falls back to collocation, which the target's description says).
    /// Unset (default): the scene target's "quadrature", collocation without one. Cells run on
    /// one level (levels.count 0 chooses 1) with the paper's α, β, γ, the symmetric form, no
    /// cap, no pose, and not with the newton algorithm (not yet).
    std::optional<Quadrature> quadrature;

    /// β of a distance with these sides: params.beta, or if it is 0 the automatic value (4
    /// for Sides::symmetric, kScanFormBeta for the scan forms).
    double beta_for(Sides sides) const;
  };
  /// The Tikhonov terms of the objective (ShapeObjectiveOptions).
  struct Tikhonov {
    double mass = 0.0;      ///< M of (M/2) ∫ m² (0)
    double gradient = 0.0;  ///< ε_m of (ε_m/2) ∫ |∇m|² (0)
  };
  /// The target: the scene's "target" unless a file is given.
  struct Target {
    /// A target cloud file (text or PLY) instead of the scene's "target"; empty (default):
    /// the scene's.
    std::string file;
  };
  /// The state solves.
  struct State {
    fe::StateBackend backend = fe::StateBackend::kCholmod;  ///< the state solver (cholmod)
    CoarseLevel coarse_levels = CoarseLevel::automatic;     ///< two-level starts (auto)
  };
  /// Multilevel optimisation (docs/formulation.md §4.8): with count = N > 1 the control
  /// problem is solved first on the N − 1 coarser levels of fe::coarsened with
  /// fe::Halving::rounded (the box halved N − 1 times, along its even axes, else every axis of
  /// at least 4 cells to (n + 1) / 2; a mesh file of order 2 its P1/Q1 level), then on each
  /// finer level in turn, each from the control of the level below prolongated (vertex
  /// controls interpolated, element controls the containing coarse element's; unchanged from a
  /// P1/Q1 level), finishing on the user's mesh, target and tolerance with
  /// optimiser.max_iterations. A coarse level has the scene's target for its body (an arc grid
  /// twice as fine as its nodes), or, for a target with as many points as the finer level's,
  /// every 2^d-th point with the volumes scaled to keep their total.
  struct Levels {
    /// N. 1: the user's mesh alone. 0 (the default): where the target has a known map, 1 +
    /// every coarser level of at least 32 elements (fe::coarser_levels; the two-level starts'
    /// smallest mesh), else 1; 1 for a cloud without a known map (a scan: there the coarse
    /// start ends at a lower ρ̃ but a larger shape error), a run from
    /// optimiser.initial_control or with a joint pose (tracking_levels).
    int count = 0;
    /// At most min(coarse_iterations, optimiser.max_iterations) iterations per coarse level
    /// (30).
    int coarse_iterations = 30;
    /// A coarse level ends once ρ̃ decreased by less than this (relative) in two iterations
    /// in a row (0.01).
    double switch_decrease = 0.01;
    /// A coarse level's tree tolerance is max(distance.tolerance, coarse_tolerance) (5e-2).
    double coarse_tolerance = 5e-2;
    /// Every level started from a coarser level's control has this move limit instead of
    /// optimiser.move_limit (0.02): its start is near its optimum already, and a step as large
    /// as a first one's curls the body far from the state it was started from
    /// (docs/formulation.md §4.8).
    double refined_move_limit = 0.02;
  };
  /// A target in the camera's frame (docs/formulation.md §8.10, §8.11): how its pose is
  /// refined from the start pose (the target's "pose" file, else `align` at rest).
  struct Pose {
    /// joint (default): the pose's twist joins the optimiser's variables; projection: each
    /// evaluation minimises the distance over the pose on its state and the optimiser sees
    /// the control alone (ShapeObjectiveOptions::pose_method).
    PoseMethod method = PoseMethod::joint;
    /// The pose's move limit as a fraction of the control's, in (0, 1] (PoseBounds::move; 1;
    /// joint only).
    double move = 1.0;
  };
  /// The run's files.
  struct Output {
    /// The run's folder (created if missing; locked while the run lasts): history.csv,
    /// summary.json, checkpoint.bin, body_NNNN.vtu, body.pvd, target.vtu, target.ply,
    /// body_final.ply and control.csv, each kept up to date as the run goes. Empty (default):
    /// no files and no checkpoint. The checkpoint's fingerprint holds a content hash of the
    /// scene file (Scene::source), so a resume needs the scene's file unchanged.
    std::string folder;
    /// Continue the run recorded in folder/checkpoint.bin (ShapeTrackingOptions::resume): the
    /// same run as an uninterrupted one (false).
    bool resume = false;
    int checkpoint_every = 5;  ///< warm-start states saved every this many iterations (5)
    int vtu_every = 10;        ///< body_NNNN.vtu every this many iterations (10; 0: start, end)
  };

  Optimiser optimiser;  ///< the optimiser and its start
  Distance distance;    ///< the distance and its form
  Tikhonov tikhonov;    ///< the Tikhonov terms
  Target target;        ///< the target
  State state;          ///< the state solves
  Levels levels;        ///< multilevel optimisation
  Pose pose;            ///< a camera-frame target's pose
  Output output;        ///< the run's files
  /// OpenMP threads of the pair sums, 0 to kMaxThreads (0, the default: OpenMP's). The FE
  /// assembly's are the caller's (set_threads); the CLI and Python set both.
  int threads = 0;
  /// The processes sharing each evaluation's pair sums (HausdorffOptions::share; the CLI:
  /// world_share()). Null (default): this process alone.
  std::shared_ptr<const WorkShare> share;
  /// Refuse an arc target grid whose estimated memory exceeds this many bytes (8 GiB).
  double memory_limit = fe::kDefaultMemoryLimit;

  /// Throws InvalidArgument naming the first invalid field by its path (e.g.
  /// "levels.refined_move_limit"; those of the objective and the optimiser included).
  void validate() const;
  /// The objective's options these settings give; β for distance.form's sides (symmetric
  /// without one: TrackingRun sets it again for the target's form, run_beta).
  ShapeObjectiveOptions objective() const;
  /// track_shape's options these settings give: the optimiser's, the checkpoint schedule, and
  /// with output.folder the checkpoint file and resume (TrackingRun::run adds the fingerprint).
  ShapeTrackingOptions tracking() const;
};

/// One level of a multilevel run (TrackingRunOptions::Levels).
struct LevelReport {
  int level = 0;                ///< halvings of the user's mesh (0: the user's mesh)
  long nodes = 0;               ///< of its mesh
  long target_points = 0;       ///< of its target
  int iterations = 0;           ///< accepted on this level
  double seconds = 0.0;         ///< wall time of this level (over all resumes)
  double rho_final = 0.0;       ///< ρ̃ at the level's best control
  std::optional<double> floor;  ///< its own floor (matched, else self)
  std::string termination;      ///< why the level ended
  /// One line: level, iterations, time, ρ̃/floor at its end.
  std::string BriefReport() const;
};

/// The result of a run: track_shape's summary (status, BriefReport) and what was tracked.
struct TrackingRunSummary : ShapeTrackingSummary {
  /// The coarse levels, coarsest first, then the user's mesh (levels > 1; else empty). The
  /// summary's own fields are the user's mesh's level, with seconds and history over all
  /// levels (history: the coarse levels' iterations first, each with its level).
  std::vector<LevelReport> levels;
  std::string target;      ///< the target's description (one line)
  long target_points = 0;  ///< points of the target cloud
  long nodes = 0;          ///< nodes of the body's mesh
  long controls = 0;       ///< control values
  /// The coarse level of the two-level starts (fe::describe_level: "cells 25 5 1", "P1 on
  /// the vertices: tet4, 778 nodes"); empty without one.
  std::string coarse_level;
};

/// Observers of a run: track_shape's (on_start, on_iteration — which may throw StopRequest —
/// and on_failure), each called after the run's files for that moment are written, and
/// on_begin.
struct TrackingRunCallbacks : ShapeTrackingCallbacks {
  /// The run is set up and its folder ready (locked, a resume's checkpoint checked), before
  /// the first state solve: the sizes and the target's description (the rest still empty).
  std::function<void(const TrackingRunSummary&)> on_begin;
};

/// The target of a run on the body `mesh` of `scene`: the cloud file options.target.file (no
/// known map), else the scene's "target" (scene_target, options.memory_limit). Throws as those.
SceneTarget tracking_target(const Scene& scene, const fe::Mesh& mesh,
                            const TrackingRunOptions& options);

/// The levels of a run of `options` on `scene` against `target`: options.levels.count, or for 0
/// (automatic) 1 + the body's coarser levels of at least 32 elements (fe::coarser_levels with
/// fe::Halving::rounded) where the target has a known map (an arc, a manufactured state), else
/// 1; always 1 for a run from
/// options.optimiser.initial_control or against a target in the camera's frame (a joint pose),
/// which run on one level.
int tracking_levels(const Scene& scene, const TrackingRunOptions& options,
                    const SceneTarget& target);

/// One tracking run, set up at construction (no file touched) and made by run().
class TrackingRun {
 public:
  /// The body of `scene` (its mesh, control space, bounds and initial control) against the
  /// target of options.target.file, else the scene's "target". `scene` must outlive the run.
  /// Throws InvalidArgument (invalid options, a missing or malformed target, dimensions that
  /// differ), FileError or ResourceError.
  TrackingRun(const Scene& scene, const TrackingRunOptions& options);
  /// The same on a body already built from `scene` (assembler and control space outlive the
  /// run) against `target` (options.target.file is ignored).
  TrackingRun(const Scene& scene, const fe::Assembler& assembler, const fe::ControlSpace& control,
              SceneTarget target, const TrackingRunOptions& options);
  ~TrackingRun();
  TrackingRun(const TrackingRun&) = delete;
  TrackingRun& operator=(const TrackingRun&) = delete;

  /// Makes the run (once). With options.out: creates and locks the folder, refuses a resume
  /// without a checkpoint or of another run, and writes the files as the run goes. Throws as
  /// track_shape (StateSolveError for a failed solve at the start or the best control,
  /// Interrupted, the callbacks' exceptions), ResourceError for a folder in use, FileError.
  TrackingRunSummary run(const TrackingRunCallbacks& callbacks = {});

  /// The fingerprints of the checkpoints run() keeps (a resume of another run is refused),
  /// without running: one per level, the coarsest first, the user's mesh's last (one for a
  /// single-level run). A level after the first starts from the control the level before it
  /// ends with; its fingerprint here has the scene's start (control.initial) in its place.
  std::vector<RunFingerprint> fingerprints() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// TrackingRun(scene, options).run(callbacks).
TrackingRunSummary run_tracking(const Scene& scene, const TrackingRunOptions& options,
                                const TrackingRunCallbacks& callbacks = {});

}  // namespace softhd

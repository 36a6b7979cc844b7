#pragma once
// Shared parts of the optimisation benchmarks (issue 6): bodies built from the scene
// files (re-meshed or translated), arc targets sampled in several ways, one tracking run
// with its measured numbers, and the CSV every benchmark writes.

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "softhd/control/scene.hpp"
#include "softhd/control/shape_tracking.hpp"
#include "softhd/control/targets.hpp"
#include "softhd/control/tracking_run.hpp"

namespace softhd::bench {

/// A body ready to optimise: the scene and, at stable addresses, its assembler and
/// control space.
struct Body {
  softhd::Scene scene;
  std::unique_ptr<fe::Assembler> assembler;
  std::unique_ptr<fe::ControlSpace> space;
  const fe::Mesh& mesh() const { return assembler->mesh(); }
};

/// data/scenes/NAME.json of the source tree.
softhd::Scene scene_file(const std::string& name);
/// The scene with `cells` elements per direction (empty: unchanged), shifted by `shift`.
Body make_body(softhd::Scene scene, const Eigen::Vector3i& cells = Eigen::Vector3i::Zero(),
               const Eigen::Vector3d& shift = Eigen::Vector3d::Zero());

/// The bending scene's arc map (its plate's length and thickness, `angle` radians).
ArcMap arc_of(const softhd::Scene& scene, double angle = M_PI);
/// u_T = T(X − shift) + shift − X at the body's nodes (the map of a translated scene).
Eigen::VectorXd arc_displacement(const ArcMap& T, const fe::Mesh& mesh,
                                 const Eigen::Vector3d& shift = Eigen::Vector3d::Zero());
/// Translates a cloud.
PointCloud shifted(const PointCloud& cloud, const Eigen::Vector3d& shift);

/// Arc targets of the plate [0, L] × [0, W] × [0, t] (`box` = the scene), each mapped by T
/// with volumes × det ∇T (docs/formulation.md §5.2):
/// a cell-centred grid with `counts` cells;
PointCloud arc_grid(const softhd::Scene& box, const ArcMap& T, const Eigen::Vector3i& counts);
/// n uniform random points of the plate;
PointCloud arc_random(const softhd::Scene& box, const ArcMap& T, int n, std::uint64_t seed);
/// n random points with density ∝ 1 + 4 X1/L (5× denser at the free end than at the clamp),
/// volumes |Ω| / (n p(X)) so they still sum to |Ω| in expectation;
PointCloud arc_nonuniform(const softhd::Scene& box, const ArcMap& T, int n, std::uint64_t seed);
/// a mapped cloud with isotropic Gaussian noise of standard deviation `sigma` added to the
/// deformed positions (a scanner's error);
PointCloud jittered(const PointCloud& cloud, double sigma, std::uint64_t seed);
/// the plate's surface only: cell centres of a grid of spacing ≈ `spacing` on its six faces,
/// weights = face areas (× det ∇T, to first order); with `random_n` > 0 instead n random
/// surface points with density ∝ 1 + 4 X1/L (a scan).
PointCloud arc_surface(const softhd::Scene& box, const ArcMap& T, double spacing, int random_n = 0,
                       std::uint64_t seed = 1);

/// What one benchmark run is asked to do.
struct RunSettings {
  /// The run as `softhd optimise` makes it (no folder), with the benchmarks' defaults: 60
  /// iterations and exact pair sums (the benchmarks compare methods explicitly).
  TrackingRunOptions run;
  bool progress = true;  ///< a line per run (and every 10 iterations) on stderr
  RunSettings();
};

/// One run's measured results with the benchmark's own parameter columns.
struct Run {
  std::vector<std::pair<std::string, std::string>> params;  ///< first CSV columns
  long nodes = 0, controls = 0, target_points = 0;
  TrackingRunSummary summary;
  std::string error;  ///< non-empty if the run threw (summary then holds what is known)
  /// Every reported number is finite (errors excluded).
  bool finite() const;
};

/// The library's TrackingRun on the body against `target` (with the known map `map`); never
/// throws for a failed run (the message goes into Run::error).
Run run_tracking(std::vector<std::pair<std::string, std::string>> params, Body& body,
                 const PointCloud& target, const std::optional<Eigen::VectorXd>& map,
                 const RunSettings& settings);

/// Writes all runs (same parameter keys) as CSV: the parameters, then the measured
/// columns (floors, final ρ̃ and its ratio, shape error, iterations, termination, times,
/// and the iteration/time at which ρ̃ first fell to 2, 1.5, 1.25 × the floor).
void write_csv(const std::string& path, const std::vector<Run>& runs);

/// Small command-line helpers shared by the benchmarks.
std::string option(int argc, char** argv, const std::string& name, const std::string& fallback);
bool has_flag(int argc, char** argv, const std::string& name);
std::string fmt(double v, int precision = 4);

}  // namespace softhd::bench

#include "softhd/control/run_fields.hpp"

#include <algorithm>
#include <cctype>
#include <cstring>

#include "softhd/control/tracking_run.hpp"
#include "softhd/error.hpp"

namespace softhd {

namespace {

// Why Python has no keyword for the run's files.
constexpr const char* kNoFiles =
    "Python: the run writes no files and keeps no checkpoint (its result is returned)";

using Options = TrackingRunOptions;

// The copy of a field of the distance's form: the form made (the defaults) where `to` has none.
template <class F>
void copy_form(const Options& from, Options& to, F field) {
  if (!from.distance.form) return;
  TargetDistance& d = to.distance.form ? *to.distance.form : to.distance.form.emplace();
  d.*field = (*from.distance.form).*field;
}

}  // namespace

// The copy of field `member` (a path of members) of TrackingRunOptions.
#define SOFTHD_COPY(member) [](const Options& f, Options& t) { t.member = f.member; }
#define SOFTHD_COPY_FORM(member) \
  [](const Options& f, Options& t) { copy_form(f, t, &TargetDistance::member); }

const std::vector<RunField>& tracking_run_fields() {
  static const std::vector<RunField> fields{
      {"optimiser.algorithm", "--algorithm", "algorithm", "", SOFTHD_COPY(optimiser.algorithm)},
      {"optimiser.hessian", "--hessian", "hessian", "", SOFTHD_COPY(optimiser.hessian)},
      {"optimiser.max_iterations", "--max-iter", "max_iter", "",
       SOFTHD_COPY(optimiser.max_iterations),
       "a limit: the iterations over all resumes (a resume may go on longer)"},
      {"optimiser.max_evaluations", "", "",
       "library only: the front ends bound a run by its iterations and seconds (the default "
       "5 x max_iterations + 20)",
       SOFTHD_COPY(optimiser.max_evaluations), "a limit: where the run stops, not its path"},
      {"optimiser.max_seconds", "--max-seconds", "max_seconds", "",
       SOFTHD_COPY(optimiser.max_seconds), "a limit: where the run stops, not its path"},
      {"optimiser.relative_change", "--rel-tol", "rel_tol", "",
       SOFTHD_COPY(optimiser.relative_change)},
      {"optimiser.move_limit", "--move-limit", "move_limit", "", SOFTHD_COPY(optimiser.move_limit)},
      {"optimiser.initial_control", "", "initial",
       "CLI: a vector of one value per control; a staged run starts from Python's result",
       SOFTHD_COPY(optimiser.initial_control)},
      {"distance.particles", "--particles", "particles", "", SOFTHD_COPY(distance.particles)},
      {"distance.volumes", "--volumes", "volumes", "", SOFTHD_COPY(distance.volumes)},
      {"distance.params.alpha", "--alpha", "alpha", "", SOFTHD_COPY(distance.params.alpha)},
      {"distance.params.beta", "--beta", "beta", "", SOFTHD_COPY(distance.params.beta)},
      {"distance.params.gamma", "--gamma", "gamma", "", SOFTHD_COPY(distance.params.gamma)},
      {"distance.params.epsilon", "--eps", "eps", "", SOFTHD_COPY(distance.params.epsilon)},
      {"distance.method", "--method", "method", "", SOFTHD_COPY(distance.method)},
      {"distance.tolerance", "--tol", "tol", "", SOFTHD_COPY(distance.tolerance)},
      {"distance.quadrature", "--quadrature", "quadrature", "", SOFTHD_COPY(distance.quadrature)},
      {"distance.form.sides", "--distance", "distance", "", SOFTHD_COPY_FORM(sides)},
      {"distance.form.cap", "--cap", "cap", "", SOFTHD_COPY_FORM(cap)},
      {"distance.form.cap_quantile", "", "",
       "the scene target's \"cap\": {\"quantile\", \"factor\"} only (a rule on the scan)",
       SOFTHD_COPY_FORM(cap_quantile)},
      {"distance.form.cap_factor", "", "",
       "the scene target's \"cap\": {\"quantile\", \"factor\"} only (a rule on the scan)",
       SOFTHD_COPY_FORM(cap_factor)},
      {"distance.form.cap_q", "--cap-q", "cap_q", "", SOFTHD_COPY_FORM(cap_q)},
      {"tikhonov.mass", "--tikhonov-mass", "tikhonov_mass", "", SOFTHD_COPY(tikhonov.mass)},
      {"tikhonov.gradient", "--tikhonov-grad", "tikhonov_grad", "", SOFTHD_COPY(tikhonov.gradient)},
      {"target.file", "--target", "target", "", SOFTHD_COPY(target.file)},
      {"state.backend", "--state-backend", "",
       "Python: cholmod only (the PETSc backends distribute the state over the ranks of "
       "mpiexec, which starts the CLI)",
       SOFTHD_COPY(state.backend)},
      {"state.coarse_levels", "--coarse-levels", "coarse_levels", "",
       SOFTHD_COPY(state.coarse_levels)},
      {"levels.count", "--levels", "levels", "", SOFTHD_COPY(levels.count)},
      {"levels.coarse_iterations", "--coarse-iterations", "coarse_iterations", "",
       SOFTHD_COPY(levels.coarse_iterations)},
      {"levels.switch_decrease", "--switch-decrease", "switch_decrease", "",
       SOFTHD_COPY(levels.switch_decrease)},
      {"levels.coarse_tolerance", "--coarse-tol", "coarse_tol", "",
       SOFTHD_COPY(levels.coarse_tolerance)},
      {"levels.refined_move_limit", "--refined-move-limit", "refined_move_limit", "",
       SOFTHD_COPY(levels.refined_move_limit)},
      {"pose.method", "--pose-method", "pose_method", "", SOFTHD_COPY(pose.method)},
      {"pose.move", "--pose-move", "pose_move", "", SOFTHD_COPY(pose.move)},
      {"output.folder", "--out", "", kNoFiles, SOFTHD_COPY(output.folder), "where the files go"},
      {"output.resume", "--resume", "", kNoFiles, SOFTHD_COPY(output.resume),
       "whether this run continues the checkpoint"},
      {"output.checkpoint_every", "--checkpoint-every", "", kNoFiles,
       SOFTHD_COPY(output.checkpoint_every)},
      {"output.vtu_every", "--vtu-every", "", kNoFiles, SOFTHD_COPY(output.vtu_every),
       "which iterations write a VTU file"},
      {"threads", "--threads", "threads", "", SOFTHD_COPY(threads)},
      {"share", "", "",
       "set by the front end: the CLI's ranks under mpiexec; Python runs in one process",
       SOFTHD_COPY(share)},
      {"memory_limit", "--max-memory", "",
       "Python: Scene.load(path, max_memory_gib) bounds the meshes; the run keeps the default",
       SOFTHD_COPY(memory_limit),
       "a bound that refuses a target grid; an accepted grid does not depend on it"},
  };
  return fields;
}

#undef SOFTHD_COPY
#undef SOFTHD_COPY_FORM

const std::vector<CliOnlyFlag>& optimise_cli_only_flags() {
  static const std::vector<CliOnlyFlag> flags{
      {"--json", "print summary.json on stdout at the end"},
      {"--quiet", "no progress lines"},
      {"--help", "the help text"},
  };
  return flags;
}

std::string name_fields(const std::string& message, FrontEnd front_end) {
  // Longest paths first, so that no path is replaced inside a longer one.
  std::vector<const RunField*> fields;
  for (const RunField& f : tracking_run_fields()) fields.push_back(&f);
  std::stable_sort(fields.begin(), fields.end(), [](const RunField* a, const RunField* b) {
    return std::strlen(a->path) > std::strlen(b->path);
  });
  auto word = [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '.';
  };
  std::string out = message;
  for (const RunField* f : fields) {
    const std::string name = front_end == FrontEnd::cli ? f->flag : f->keyword;
    const std::string path = f->path;
    if (name.empty() || path.find('.') == std::string::npos) continue;  // top-level: as named
    for (std::size_t at = out.find(path); at != std::string::npos; at = out.find(path, at)) {
      const std::size_t end = at + path.size();
      // A whole path: no name character before it, none but a sentence's full stop after it.
      const bool starts = at == 0 || !word(out[at - 1]);
      const bool ends = end == out.size() || !word(out[end]) ||
                        (out[end] == '.' && (end + 1 == out.size() || out[end + 1] == ' '));
      if (starts && ends) {
        out.replace(at, path.size(), name);
        at += name.size();
      } else {
        at = end;
      }
    }
  }
  return out;
}

void validate_naming_fields(const TrackingRunOptions& options, FrontEnd front_end) {
  try {
    options.validate();
  } catch (const InvalidArgument& e) {
    const std::string named = name_fields(e.what(), front_end);
    if (named != e.what()) throw InvalidArgument(named);
    for (const RunField& f : tracking_run_fields()) {
      const std::string name = front_end == FrontEnd::cli ? f.flag : f.keyword;
      if (name.empty()) continue;
      TrackingRunOptions alone;
      f.copy(options, alone);
      try {
        alone.validate();
      } catch (const InvalidArgument&) {
        throw InvalidArgument(name + ": " + named);
      }
    }
    throw;
  }
}

}  // namespace softhd

#include "softhd/control/run_fields.hpp"

#include <algorithm>
#include <cctype>
#include <cstring>

namespace softhd {

namespace {

// Why Python has no keyword for the run's files.
constexpr const char* kNoFiles =
    "Python: the run writes no files and keeps no checkpoint (its result is returned)";

}  // namespace

const std::vector<RunField>& tracking_run_fields() {
  static const std::vector<RunField> fields{
      {"optimiser.algorithm", "--algorithm", "algorithm", ""},
      {"optimiser.max_iterations", "--max-iter", "max_iter", ""},
      {"optimiser.max_evaluations", "", "",
       "library only: the front ends bound a run by its iterations and seconds (the default "
       "5 x max_iterations + 20)"},
      {"optimiser.max_seconds", "--max-seconds", "max_seconds", ""},
      {"optimiser.relative_change", "--rel-tol", "rel_tol", ""},
      {"optimiser.move_limit", "--move-limit", "move_limit", ""},
      {"optimiser.initial_control", "", "initial",
       "CLI: a vector of one value per control; a staged run starts from Python's result"},
      {"distance.particles", "--particles", "particles", ""},
      {"distance.volumes", "--volumes", "volumes", ""},
      {"distance.params.alpha", "--alpha", "alpha", ""},
      {"distance.params.beta", "--beta", "beta", ""},
      {"distance.params.gamma", "--gamma", "gamma", ""},
      {"distance.params.epsilon", "--eps", "eps", ""},
      {"distance.method", "--method", "method", ""},
      {"distance.tolerance", "--tol", "tol", ""},
      {"distance.form.sides", "--distance", "distance", ""},
      {"distance.form.cap", "--cap", "cap", ""},
      {"distance.form.cap_quantile", "", "",
       "the scene target's \"cap\": {\"quantile\", \"factor\"} only (a rule on the scan)"},
      {"distance.form.cap_factor", "", "",
       "the scene target's \"cap\": {\"quantile\", \"factor\"} only (a rule on the scan)"},
      {"distance.form.cap_q", "--cap-q", "cap_q", ""},
      {"tikhonov.mass", "--tikhonov-mass", "tikhonov_mass", ""},
      {"tikhonov.gradient", "--tikhonov-grad", "tikhonov_grad", ""},
      {"target.file", "--target", "target", ""},
      {"state.backend", "--state-backend", "",
       "Python: cholmod only (the PETSc backends distribute the state over the ranks of "
       "mpiexec, which starts the CLI)"},
      {"state.coarse_levels", "--coarse-levels", "coarse_levels", ""},
      {"levels.count", "--levels", "levels", ""},
      {"levels.coarse_iterations", "--coarse-iterations", "coarse_iterations", ""},
      {"levels.switch_decrease", "--switch-decrease", "switch_decrease", ""},
      {"levels.coarse_tolerance", "--coarse-tol", "coarse_tol", ""},
      {"levels.refined_move_limit", "--refined-move-limit", "refined_move_limit", ""},
      {"pose.move", "--pose-move", "pose_move", ""},
      {"output.folder", "--out", "", kNoFiles},
      {"output.resume", "--resume", "", kNoFiles},
      {"output.checkpoint_every", "--checkpoint-every", "", kNoFiles},
      {"output.vtu_every", "--vtu-every", "", kNoFiles},
      {"threads", "--threads", "threads", ""},
      {"share", "", "",
       "set by the front end: the CLI's ranks under mpiexec; Python runs in one process"},
      {"memory_limit", "--max-memory", "",
       "Python: Scene.load(path, max_memory_gib) bounds the meshes; the run keeps the default"},
  };
  return fields;
}

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

}  // namespace softhd

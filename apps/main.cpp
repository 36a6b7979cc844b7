// softhd: command-line front end. Dispatches to the subcommands; turns every error
// into one line on stderr and a non-zero exit code (2 for bad input). Under mpiexec, an
// error of some ranks only ends the whole job (MPI_Abort) instead of leaving it waiting.

#include <exception>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "commands.hpp"
#include "failure.hpp"
#include "softhd/error.hpp"
#include "softhd/work_share.hpp"
#if SOFTHD_WITH_MPI
#include "softhd/mpi/work_share.hpp"
#endif

#if defined(SOFTHD_WITH_MPI) && SOFTHD_WITH_MPI
#include <petscsys.h>
#endif

namespace {

#if defined(SOFTHD_WITH_MPI) && SOFTHD_WITH_MPI
// PETSc, and with it MPI, for the whole run: initialised once here, never by the library
// (fe/petsc_state.hpp). PETSc sees only the program name (softhd's own options are not
// PETSc's); its options come from the environment variable PETSC_OPTIONS.
class PetscSession {
 public:
  explicit PetscSession(char* program) {
    static char* args[] = {program, nullptr};
    int argc = 1;
    char** argv = args;
    ok_ = PetscInitialize(&argc, &argv, nullptr, nullptr) == 0;
  }
  ~PetscSession() {
    if (ok_) PetscFinalize();
  }
  PetscSession(const PetscSession&) = delete;
  PetscSession& operator=(const PetscSession&) = delete;

 private:
  bool ok_ = false;
};
#endif

const char* kUsage = R"(usage: softhd COMMAND [options]

commands:
  align      pose of a scan (camera frame) on a body, by the distance
  distance   regularised Hausdorff distance between two point clouds
  forward    equilibrium of a scene's body for a given fiber tension
  optimise   fiber tension that makes a body match a target cloud

Run 'softhd COMMAND --help' for the options of a command.

exit status: 0 done; 1 a numerical failure on valid input (a state solve that does not
converge), or an internal error (a bug in softhd: please report it); 2 bad input or refused,
with one line on stderr naming the file, key or flag.
)";

/// A stream that drops what it is given (the error lines of ranks other than 0).
std::ostream& quiet() {
  static std::ostream sink(nullptr);
  return sink;
}

}  // namespace

int main(int argc, char** argv) {
#if SOFTHD_WITH_MPI
  // Under mpiexec the ranks share the pair sums (softhd distance); started alone, one rank.
  const softhd::mpi::Session mpi(&argc, &argv);
#endif
  // Every rank reads the same inputs and meets the same errors: rank 0 reports them.
  std::ostream& err = softhd::world_rank() == 0 ? std::cerr : quiet();
  const std::vector<std::string> all(argv + 1, argv + argc);
  if (all.empty() || all[0] == "--help" || all[0] == "-h" || all[0] == "help") {
    std::cout << kUsage;
    return all.empty() ? 2 : 0;
  }
  const std::string command = all[0];
#if defined(SOFTHD_WITH_MPI) && SOFTHD_WITH_MPI
  // Only a forward solve or an optimisation on a PETSc backend starts PETSc (which starts
  // MPI if the session above did not): every other run pays no PETSc start-up.
  bool wants_petsc = false;
  for (size_t k = 1; k + 1 < all.size(); ++k)
    if (all[k] == "--state-backend" && all[k + 1].rfind("petsc", 0) == 0) wants_petsc = true;
  std::unique_ptr<PetscSession> petsc;
  const bool state_command = command == "forward" || command == "optimise" || command == "optimize";
  if (state_command && wants_petsc) petsc = std::make_unique<PetscSession>(argv[0]);
#endif
  const std::vector<std::string> rest(all.begin() + 1, all.end());
  int code = 0;
  std::string error;  // the one line of a failed command
  try {
    if (command == "align") return softhd::cli::run_align(rest);
    if (command == "distance") return softhd::cli::run_distance(rest);
    if (command == "forward") return run_forward(argc - 1, argv + 1);
    if (command == "optimise" || command == "optimize") return softhd::cli::run_optimise(rest);
    err << "softhd: unknown command '" << command << "' (see softhd --help)\n";
    return 2;
  } catch (const softhd::InternalError& e) {
    // A bug in softhd, not bad input: exit 1 (its message says "internal error").
    std::tie(code, error) = std::pair(1, std::string(e.what()));
  } catch (const softhd::NumericalError& e) {
    // Valid input on which the numerics failed (e.g. a state solve): exit 1, not "bad input".
    std::tie(code, error) = std::pair(1, std::string("error: ") + e.what());
  } catch (const softhd::Error& e) {
    std::tie(code, error) = std::pair(2, std::string("error: ") + e.what());
  } catch (const std::filesystem::filesystem_error& e) {
    // The environment, not softhd: a path that cannot be read, created or listed.
    std::tie(code, error) = std::pair(2, std::string("error: ") + e.what());
  } catch (const std::bad_alloc&) {
    std::tie(code, error) = std::pair(1, std::string("error: out of memory"));
  } catch (const std::exception& e) {
    std::tie(code, error) = std::pair(1, std::string("internal error: ") + e.what());
  }
  return softhd::cli::report_failure(command, code, error);
}

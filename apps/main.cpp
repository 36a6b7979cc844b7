// softhd: command-line front end. Dispatches to the subcommands; turns every error
// into one line on stderr and a non-zero exit code (2 for bad input).

#include <exception>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "commands.hpp"
#include "softhd/error.hpp"
#include "softhd/work_share.hpp"
#if SOFTHD_WITH_MPI
#include "softhd/mpi/work_share.hpp"
#endif

namespace {

const char* kUsage = R"(usage: softhd COMMAND [options]

commands:
  distance   regularised Hausdorff distance between two point clouds
  forward    equilibrium of a scene's body for a given fiber tension
  optimise   fiber tension that makes a body match a target cloud

Run 'softhd COMMAND --help' for the options of a command.
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
  const std::vector<std::string> rest(all.begin() + 1, all.end());
  try {
    if (command == "distance") return softhd::cli::run_distance(rest);
    if (command == "forward") return run_forward(argc - 1, argv + 1);
    if (command == "optimise" || command == "optimize") return softhd::cli::run_optimise(rest);
    err << "softhd: unknown command '" << command << "' (see softhd --help)\n";
    return 2;
  } catch (const softhd::Error& e) {
    err << "softhd " << command << ": error: " << e.what() << '\n';
    return 2;
  } catch (const std::filesystem::filesystem_error& e) {
    // The environment, not softhd: a path that cannot be read, created or listed.
    err << "softhd " << command << ": error: " << e.what() << '\n';
    return 2;
  } catch (const std::bad_alloc&) {
    err << "softhd " << command << ": error: out of memory\n";
    return 1;
  } catch (const std::exception& e) {
    err << "softhd " << command << ": internal error: " << e.what() << '\n';
    return 1;
  }
}

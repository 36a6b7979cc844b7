#pragma once
// The softhd subcommands. Each takes the tokens after its name and returns the
// process exit code; bad input is thrown as softhd::Error (main prints it, exit 2).

#include <string>
#include <vector>

namespace softhd::cli {

int run_align(const std::vector<std::string>& args);
int run_distance(const std::vector<std::string>& args);
int run_optimise(const std::vector<std::string>& args);

}  // namespace softhd::cli

/// softhd forward SCENE [...]: solves the state of a scene (argv[0] is "forward");
/// 0 success, 1 numerical failure (reported), 2 bad input (one line on stderr).
int run_forward(int argc, char** argv);

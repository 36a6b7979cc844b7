#pragma once
// Subcommands of the softhd command-line tool. Each takes its own argv (argv[0] is the
// subcommand name) and returns the process exit code: 0 success, 1 numerical failure
// (reported), 2 bad input (one line on stderr).

/// softhd forward SCENE [...]: solves the state of a scene (issue 4, item 8).
int run_forward(int argc, char** argv);

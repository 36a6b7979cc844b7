#include <cstring>
#include <iostream>
#include <string>

#include "commands.hpp"

int main(int argc, char** argv) {
  if (argc >= 2 && std::strcmp(argv[1], "forward") == 0) return run_forward(argc - 1, argv + 1);
  std::cout << "softhd: subcommands are coming\n";
  return 0;
}

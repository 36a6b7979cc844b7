#include <iostream>
#include <string>

int main(int argc, char** argv) {
  (void)argc;
  (void)argv;
  std::cout << "softhd: subcommands are coming\n";
  return 0;
}

// The main() of the GoogleTest executables that use PETSc (run under mpiexec): PETSc, and
// with it MPI, initialised around the tests, as softhd's own main does for its commands.

#include <gtest/gtest.h>
#include <petscsys.h>

int main(int argc, char** argv) {
  if (PetscInitialize(&argc, &argv, nullptr, nullptr) != 0) return 1;
  ::testing::InitGoogleTest(&argc, argv);
  const int result = RUN_ALL_TESTS();
  PetscFinalize();
  return result;
}

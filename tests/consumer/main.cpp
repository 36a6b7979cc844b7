// Links against an installed softhd: two single-point clouds 0.5 apart have ρ̃ = 0.5.
#include <cmath>
#include <cstdio>
#include <softhd/hausdorff.hpp>

int main() {
  const softhd::PointCloud x(Eigen::RowVector3d(0.0, 0.0, 0.0));
  const softhd::PointCloud y(Eigen::RowVector3d(0.0, 0.0, 0.5));
  const double rho = softhd::hausdorff(x, y).rho;
  std::printf("rho = %.17g\n", rho);
  return std::fabs(rho - 0.5) < 1e-15 ? 0 : 1;
}

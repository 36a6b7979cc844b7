#pragma once
// Wall seconds since a steady-clock time (internal): the one timer of the Newton solvers
// (fe/newton.cpp, fe/petsc/petsc_newton.cpp) and the tangent solver.

#include <chrono>

namespace softhd::detail {

using Clock = std::chrono::steady_clock;

inline double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

}  // namespace softhd::detail

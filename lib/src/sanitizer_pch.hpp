// The precompiled header of the library in the sanitizer tree (SOFTHD_LIB_PCH, set by
// tests/sanitize.cmake): Eigen and the standard headers most library files include, parsed
// once per build instead of in every file. The main (g++ Release) build does not use it.
#pragma once

#include <Eigen/Core>
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>
#include <vector>

// The precompiled header of the test executables in the sanitizer tree (SOFTHD_TEST_PCH,
// set by tests/sanitize.cmake): the headers most test files include, parsed once instead of
// in every test file. Only third-party and standard headers, so that it is rebuilt only when
// the compiler flags change; the main (g++ Release) build does not use it.
#pragma once

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

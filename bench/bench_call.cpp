// The C++ side of bench/bench_python.py: the time of one softhd::hausdorff call (target built,
// then evaluated) on two cloud files, as a C++ caller with PointClouds in hand pays it.
//
//   bench_call MOVING TARGET [--repeats 5] [--threads 0] [--method exact] [--grad]
//
// Prints one JSON object: rho, the minimum and median wall seconds over the repeats.

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "softhd/hausdorff.hpp"
#include "softhd/io/cloud_io.hpp"

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr,
                 "usage: bench_call MOVING TARGET [--repeats R] [--threads T] "
                 "[--method M] [--grad]\n");
    return 2;
  }
  int repeats = 5;
  softhd::HausdorffOptions options;
  softhd::HausdorffRequest request;
  for (int i = 3; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--repeats" && i + 1 < argc) {
      repeats = std::max(1, std::stoi(argv[++i]));
    } else if (a == "--threads" && i + 1 < argc) {
      options.threads = std::stoi(argv[++i]);
    } else if (a == "--method" && i + 1 < argc) {
      options.method = softhd::method_from_string(argv[++i]);
    } else if (a == "--grad") {
      request.gradient_points = true;
    } else {
      std::fprintf(stderr, "bench_call: unknown argument %s\n", a.c_str());
      return 2;
    }
  }
  const softhd::PointCloud X = softhd::read_cloud(argv[1]);
  const softhd::PointCloud Y = softhd::read_cloud(argv[2]);
  std::vector<double> seconds;
  double rho = 0.0;
  for (int r = 0; r < repeats; ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    rho = softhd::hausdorff(X, Y, options, request).rho;
    seconds.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  std::sort(seconds.begin(), seconds.end());
  std::printf("{\"rho\": %.17g, \"min_seconds\": %.9g, \"median_seconds\": %.9g}\n", rho,
              seconds.front(), seconds[seconds.size() / 2]);
  return 0;
}

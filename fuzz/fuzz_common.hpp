#pragma once
// Shared by the libFuzzer targets: every input must either parse or be refused with a
// softhd::Error. Anything else (another exception, a sanitizer report, a hang) is a
// finding: an uncaught exception aborts, which libFuzzer reports as a crash.

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "softhd/error.hpp"
#include "softhd/point_cloud.hpp"

namespace softhd::fuzz {

/// Aborts (a finding) unless the cloud holds only finite coordinates and positive volumes.
inline void check_cloud(const PointCloud& c) {
  if (c.size() < 1 || !c.points().allFinite() || !(c.volumes().array() > 0.0).all() ||
      !std::isfinite(c.total_volume()))
    std::abort();
}

/// Runs `parse` on the input; softhd::Error is the expected refusal.
template <class F>
int run(const std::uint8_t* data, std::size_t size, F&& parse) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  try {
    parse(bytes);
  } catch (const Error&) {
    // refused with a message: fine
  }
  return 0;
}

}  // namespace softhd::fuzz

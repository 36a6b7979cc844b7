// One-line reports of the optimiser's and the shape-tracking run's summaries.

#include <cstdio>

#include "softhd/control/bounded_optimizer.hpp"
#include "softhd/control/shape_tracking.hpp"

namespace softhd {

std::string BoundedOptimizerSummary::BriefReport() const {
  char line[320];
  std::snprintf(line, sizeof line,
                "%s (%s): %d iterations, %d evaluations (%d failed), J %.6g -> %.6g, %.3g s",
                to_string(status).c_str(), termination.c_str(), iterations, evaluations,
                failed_evaluations, initial_value, final_value, seconds);
  return line;
}

std::string ShapeTrackingSummary::BriefReport() const {
  char over[64] = "";
  if (floor()) std::snprintf(over, sizeof over, " (%.3g x floor)", rho_final / *floor());
  char line[384];
  std::snprintf(line, sizeof line,
                "%s (%s): %d iterations, %d evaluations (%d failed), rho %.6g -> %.6g%s, %.3g s",
                to_string(status).c_str(), termination.c_str(), iterations, evaluations,
                failed_evaluations, rho_start, rho_final, over, seconds);
  return line;
}

}  // namespace softhd

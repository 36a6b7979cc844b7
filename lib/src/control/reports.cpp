// One-line reports of the optimiser's and the shape-tracking run's summaries.

#include <cstdio>

#include "softhd/control/bounded_optimizer.hpp"
#include "softhd/control/shape_tracking.hpp"
#include "softhd/control/tracking_run.hpp"

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

std::string LevelReport::BriefReport() const {
  char over[64] = "";
  if (floor)
    std::snprintf(over, sizeof over, ", rho %.6g (%.3g x its floor)", rho_final,
                  rho_final / *floor);
  char line[384];
  std::snprintf(line, sizeof line,
                "level %d (%ld nodes, %ld target points): %d iterations, %.3g s%s; %s", level,
                nodes, target_points, iterations, seconds, over, termination.c_str());
  return line;
}

}  // namespace softhd

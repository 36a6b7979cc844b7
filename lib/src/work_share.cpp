// The cost split of a work share, and the serial world share of builds without MPI.

#include "softhd/work_share.hpp"

#include <algorithm>
#include <numeric>

namespace softhd {

UnitRange split_by_cost(const std::vector<double>& cost, int size, int rank) {
  const std::size_t n = cost.size();
  if (size <= 1) return {0, n};
  const double total = std::accumulate(cost.begin(), cost.end(), 0.0);
  const bool by_count = !(total > 0.0);
  const double per = (by_count ? static_cast<double>(n) : total) / size;
  // Unit u goes to process floor(midpoint(u) / per): the same prefix sums on every
  // process, so the runs are contiguous, disjoint and cover every unit.
  UnitRange r{n, n};
  bool found = false;
  double before = 0.0;
  for (std::size_t u = 0; u < n; ++u) {
    const double c = by_count ? 1.0 : cost[u];
    const int owner = std::min(size - 1, static_cast<int>((before + 0.5 * c) / per));
    before += c;
    if (owner == rank && !found) {
      r.first = u;
      found = true;
    }
    if (owner > rank) {
      if (!found) r.first = u;
      r.last = u;
      return r;
    }
  }
  if (!found) r.first = n;
  return r;
}

#if !defined(SOFTHD_WITH_MPI)
std::shared_ptr<const WorkShare> world_share() { return nullptr; }
int world_rank() { return 0; }
int world_size() { return 1; }
#endif

}  // namespace softhd

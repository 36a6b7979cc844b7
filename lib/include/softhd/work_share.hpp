#pragma once
/// \file work_share.hpp
/// How the pair sums of an evaluation are shared between processes.
///
/// A WorkShare names a group of processes that make the same calls on the same data.
/// Set HausdorffOptions::share to one and every pair pass (and nearest-distance query) of
/// each evaluation is split across the group: each process computes the sums of its share
/// of the outer points (contiguous runs balanced by cost), and the per-point sums are then
/// summed over the group, which completes them exactly (each entry is computed by one
/// process and is zero on the others). The chain rule then runs on every process on the same
/// numbers, so every process holds the whole result (distance, fields, gradients), equal
/// to the serial one (docs/scaling.md §1).
///
/// Null share (the default): this process computes everything. The MPI implementation,
/// softhd::mpi::work_share(MPI_Comm), is in softhd/mpi/work_share.hpp (SOFTHD_WITH_MPI
/// builds). Every process of a group must evaluate the same clouds with the same options,
/// in the same order, from one thread at a time (the calls are collective).

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

namespace softhd {

/// A group of processes that share the work of each pass (interface).
class WorkShare {
 public:
  virtual ~WorkShare() = default;
  /// Number of processes in the group (≥ 1).
  virtual int size() const = 0;
  /// This process's rank in the group, 0 ≤ rank() < size().
  virtual int rank() const = 0;
  /// Elementwise sum over the group, in place (collective; n equal on every process).
  virtual void sum(double* data, std::size_t n) const = 0;
  /// Elementwise sum over the group, in place (collective; n equal on every process).
  virtual void sum(std::int64_t* data, std::size_t n) const = 0;
};

/// Units [first, last) of one process.
struct UnitRange {
  std::size_t first = 0;  ///< the first unit of the run
  std::size_t last = 0;   ///< one past the last unit of the run
};

/// The contiguous split of units 0..n−1 with costs `cost` (≥ 0, identical on every process)
/// into `size` runs of nearly equal cost: process r takes the units whose cost midpoint lies
/// in [r, r + 1)·total/size. Deterministic; all costs zero: split by count.
UnitRange split_by_cost(const std::vector<double>& cost, int size, int rank);

/// The share over every process of the job: in SOFTHD_WITH_MPI builds, MPI_COMM_WORLD when
/// MPI is initialised and the job has more than one process; otherwise null (serial).
/// Collective over every process in MPI builds (it duplicates MPI_COMM_WORLD).
std::shared_ptr<const WorkShare> world_share();

/// This process's rank in MPI_COMM_WORLD (0 without MPI or before MPI_Init; not collective):
/// programs print from rank 0.
int world_rank();

/// The number of processes in MPI_COMM_WORLD (1 without MPI or before MPI_Init; not
/// collective).
int world_size();

}  // namespace softhd

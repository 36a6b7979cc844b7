#pragma once
/// \file mpi/work_share.hpp
/// MPI for the pair sums (SOFTHD_WITH_MPI builds only): a WorkShare over a communicator,
/// the MPI session of a program, and how a program ends when one rank fails.
///
///     softhd::mpi::Session mpi(&argc, &argv);          // MPI_Init, MPI_Finalize
///     softhd::HausdorffOptions options;
///     options.share = softhd::mpi::work_share(MPI_COMM_WORLD);
///     // every rank: the same clouds, the same calls; every rank gets the whole result

#include <mpi.h>

#include <memory>

#include "softhd/work_share.hpp"

namespace softhd::mpi {

/// The processes of `comm` (duplicated: the share's messages never mix with the caller's).
/// Throws InvalidArgument if MPI is not initialised or comm is MPI_COMM_NULL.
std::shared_ptr<const WorkShare> work_share(MPI_Comm comm);

/// Initialises MPI (MPI_THREAD_FUNNELED: OpenMP threads inside a rank, MPI calls from the
/// main thread) when the program was started by mpiexec (its environment names the job:
/// OMPI_COMM_WORLD_SIZE, PMI_SIZE or PMIX_RANK) and MPI is not initialised yet, and
/// finalises it on destruction if it initialised it. Started without mpiexec, the program
/// runs as one process without MPI (world_share() is null), at no start-up cost.
class Session {
 public:
  /// MPI_Init_thread(argc, argv, MPI_THREAD_FUNNELED, ...) under mpiexec, unless MPI is
  /// initialised.
  Session(int* argc, char*** argv);
  /// MPI_Finalize if this session initialised MPI.
  ~Session();
  Session(const Session&) = delete;
  Session& operator=(const Session&) = delete;

 private:
  bool owner_ = false;
};

/// After an error on this rank of a Session's MPI_COMM_WORLD: waits up to `seconds` for
/// every rank to report an error too (bad input meets every rank alike, at about the same
/// time). True if they all did — each may then return its exit code as usual — or if MPI
/// is not running or has one rank. False if some rank is still computing: it waits, or
/// will, in a collective call this rank never joins, so the caller must abort_world().
bool all_ranks_failed(double seconds);

/// Ends every rank of the job with exit code `code` (MPI_Abort), after flushing stdout and
/// stderr; without MPI, ends this process.
[[noreturn]] void abort_world(int code);

}  // namespace softhd::mpi

#pragma once
// How a failed command ends: one line on stderr (rank 0's under mpiexec, where every rank
// meets bad input alike) and its exit code; under mpiexec, when only some ranks failed, the
// end of the whole job, since the others would wait for them in a collective call.

#include <iostream>
#include <string>

#include "softhd/work_share.hpp"
#if SOFTHD_WITH_MPI
#include "softhd/mpi/work_share.hpp"
#endif

namespace softhd::cli {

/// Prints "softhd COMMAND: WHAT" and returns `code`, or ends the job (MPI_Abort) with it.
inline int report_failure(const std::string& command, int code, const std::string& what) {
  if (world_rank() == 0) std::cerr << "softhd " << command << ": " << what << '\n';
#if SOFTHD_WITH_MPI
  if (!mpi::all_ranks_failed(10.0)) {
    if (world_rank() != 0)
      std::cerr << "softhd " << command << " (rank " << world_rank() << "): " << what << '\n';
    mpi::abort_world(code);
  }
#endif
  return code;
}

}  // namespace softhd::cli

// The WorkShare over an MPI communicator (SOFTHD_WITH_MPI builds): sums are MPI_Allreduce
// in place, in chunks that fit MPI's int counts.

#include <mpi.h>

#include <algorithm>
#include <chrono>
#include <climits>
#include <cstdio>
#include <cstdlib>
#include <thread>

#include "softhd/error.hpp"
#include "softhd/mpi/work_share.hpp"

namespace softhd::mpi {

namespace {

class MpiShare final : public WorkShare {
 public:
  explicit MpiShare(MPI_Comm comm) {
    MPI_Comm_dup(comm, &comm_);
    MPI_Comm_size(comm_, &size_);
    MPI_Comm_rank(comm_, &rank_);
  }
  ~MpiShare() override {
    int finalized = 0;
    MPI_Finalized(&finalized);
    if (!finalized) MPI_Comm_free(&comm_);
  }
  MpiShare(const MpiShare&) = delete;
  MpiShare& operator=(const MpiShare&) = delete;

  int size() const override { return size_; }
  int rank() const override { return rank_; }
  void sum(double* data, std::size_t n) const override { reduce(data, n, MPI_DOUBLE); }
  void sum(std::int64_t* data, std::size_t n) const override { reduce(data, n, MPI_INT64_T); }

 private:
  template <class T>
  void reduce(T* data, std::size_t n, MPI_Datatype type) const {
    if (size_ == 1) return;
    constexpr std::size_t kChunk = std::size_t{1} << 28;  // well below INT_MAX
    for (std::size_t at = 0; at < n; at += kChunk) {
      const int count = static_cast<int>(std::min(kChunk, n - at));
      MPI_Allreduce(MPI_IN_PLACE, data + at, count, type, MPI_SUM, comm_);
    }
  }
  MPI_Comm comm_ = MPI_COMM_NULL;
  int size_ = 1, rank_ = 0;
};

bool initialised() {
  int init = 0, finalized = 0;
  MPI_Initialized(&init);
  MPI_Finalized(&finalized);
  return init && !finalized;
}

}  // namespace

std::shared_ptr<const WorkShare> work_share(MPI_Comm comm) {
  if (!initialised()) throw InvalidArgument("work_share: MPI is not initialised");
  if (comm == MPI_COMM_NULL) throw InvalidArgument("work_share: comm is MPI_COMM_NULL");
  return std::make_shared<MpiShare>(comm);
}

bool launched_by_mpiexec() {
  for (const char* var : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_RANK"})
    if (std::getenv(var) != nullptr) return true;
  return false;
}

namespace {
// The communicator of failure reports (a duplicate of MPI_COMM_WORLD made by the Session, so
// that a report never matches a collective call of the computation).
MPI_Comm failure_comm = MPI_COMM_NULL;
}  // namespace

Session::Session(int* argc, char*** argv) {
  if (!initialised() && launched_by_mpiexec()) {
    int provided = 0;
    MPI_Init_thread(argc, argv, MPI_THREAD_FUNNELED, &provided);
    owner_ = true;
  }
  if (initialised() && failure_comm == MPI_COMM_NULL) MPI_Comm_dup(MPI_COMM_WORLD, &failure_comm);
}

Session::~Session() {
  if (failure_comm != MPI_COMM_NULL && initialised()) MPI_Comm_free(&failure_comm);
  failure_comm = MPI_COMM_NULL;
  if (owner_ && initialised()) MPI_Finalize();
}

bool all_ranks_failed(double seconds) {
  if (!initialised() || failure_comm == MPI_COMM_NULL) return true;
  int size = 1;
  MPI_Comm_size(failure_comm, &size);
  if (size == 1) return true;
  // A barrier that only failing ranks enter: complete once every rank has failed.
  MPI_Request request = MPI_REQUEST_NULL;
  MPI_Ibarrier(failure_comm, &request);
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  int done = 0;
  while (true) {
    MPI_Test(&request, &done, MPI_STATUS_IGNORE);
    if (done || std::chrono::steady_clock::now() >= end) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return done != 0;  // else the request stays pending: the caller aborts the job
}

void abort_world(int code) {
  std::fflush(stdout);
  std::fflush(stderr);
  if (initialised()) MPI_Abort(MPI_COMM_WORLD, code);
  std::_Exit(code);
}

}  // namespace softhd::mpi

namespace softhd {

std::shared_ptr<const WorkShare> world_share() {
  if (!mpi::initialised()) return nullptr;
  int size = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  if (size == 1) return nullptr;
  return mpi::work_share(MPI_COMM_WORLD);
}

int world_rank() {
  if (!mpi::initialised()) return 0;
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  return rank;
}

int world_size() {
  if (!mpi::initialised()) return 1;
  int size = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  return size;
}

}  // namespace softhd

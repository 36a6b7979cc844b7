#pragma once
/// \file run_log.hpp
/// The checkpoint of a shape-tracking run: an append-only binary log of every objective
/// evaluation the optimiser asked for (x, J, ρ̃, A, B, gradient, timings — bitwise) with a
/// fingerprint of the problem up front, and beside it (file `<log>.states`, rewritten
/// atomically at each accepted iteration) the objective's warm-start states and the number
/// of evaluations they follow.
///
/// A resumed run starts the optimiser again from the beginning and serves its evaluations
/// from the log (checking that each x matches bitwise) until it reaches that number; then
/// the warm-start states are restored and real evaluations continue. For a deterministic
/// optimiser and objective the resumed run is therefore the uninterrupted run, whatever
/// state the optimiser keeps internally.
///
/// Files: 8 magic bytes ("SHDLOG01", "SHDSTA01"), then records [kind u8][payload length
/// u64][payload][FNV-1a 64 of kind, length and payload], little-endian doubles stored
/// bitwise. Log kinds: 'H' run id and fingerprint (first, once), 'E' one evaluation, 'P' one
/// Hessian-vector product (optimiser newton: x, the direction v, H v, or its failure); the
/// states file holds one 'S' record (run id, counts, states). A torn last log record (a
/// run killed while writing it) is dropped; anything else malformed is refused.

#include <Eigen/Core>
#include <cstdint>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include "softhd/control/shape_objective.hpp"
#include "softhd/fe/newton.hpp"

namespace softhd {

/// What a run depends on, as key → value text; a resume must match it key by key.
using RunFingerprint = std::map<std::string, std::string>;

/// FNV-1a 64-bit hash of bytes, as 16 hex digits (content hashes for fingerprints).
std::string content_hash(const void* data, std::size_t bytes);
/// Exact text of a double (hex float), for fingerprints.
std::string exact_text(double value);

/// One evaluation as the optimiser saw it, or (with a direction) one Hessian-vector product.
struct LoggedEvaluation {
  Eigen::VectorXd x;       ///< the control the optimiser asked about
  bool gradient = false;   ///< the optimiser asked for the gradient
  ShapeEvaluation result;  ///< what the objective returned (a product: H v in gradient)
  double seconds = 0.0;    ///< the run's wall time (over all resumes) when it ended
  /// Empty: an evaluation. Else a Hessian-vector product at x in this direction v: its result
  /// holds status (ok, or state_failed with the failure), H v as `gradient`, nothing else.
  Eigen::VectorXd direction;
};

/// The objective's warm-start states after a given number of evaluations.
struct RunSnapshot {
  std::int64_t evaluations = 0;   ///< evaluations (and Hessian-vector products) logged before it
  std::int64_t iterations = 0;    ///< accepted iterations by then
  std::vector<WarmStart> states;  ///< StatePath::warm_starts(), most recent first
  fe::State best;  ///< the state of the best control so far (the final solve starts there)
};

/// A checkpoint as read back: the evaluations the states follow, and the states.
struct RunLog {
  RunFingerprint fingerprint;                 ///< what the run depends on
  std::uint64_t run_id = 0;                   ///< ties the states file to its log
  std::vector<LoggedEvaluation> evaluations;  ///< those the states follow, in order
  RunSnapshot snapshot;                       ///< the states (if has_snapshot)
  bool has_snapshot = false;                  ///< false: no states file, nothing to replay
};

/// Parses a log's bytes (every whole evaluation record, no states); `source` names it in
/// errors. Throws FileError (naming the byte offset) for anything but a torn last record.
RunLog parse_run_log(const std::string& bytes, const std::string& source);
/// Parses a states file's bytes; sets *run_id. Throws FileError.
RunSnapshot parse_run_states(const std::string& bytes, const std::string& source,
                             std::uint64_t* run_id);
/// Keeps the log's evaluations the states follow and attaches the states. Throws FileError
/// if they belong to another run or count more evaluations than the log holds.
void attach_states(RunLog& log, std::uint64_t run_id, RunSnapshot states,
                   const std::string& source);
/// Reads a log and its states file (without one, nothing is replayed). Throws FileError
/// (also for a directory or an unreadable file).
RunLog read_run_log(const std::string& path);

/// Throws InvalidArgument naming the first key whose value differs (or that only one of
/// the two has), e.g. "checkpoint.bin was written for another run: scene differs".
void check_fingerprint(const RunFingerprint& stored, const RunFingerprint& current,
                       const std::string& source);

/// Writes a log: a new file with the fingerprint, then appended records, each flushed
/// to the operating system as soon as it is written (a killed process loses nothing).
class RunLogWriter {
 public:
  /// Creates (truncates) `path` and writes the fingerprint, and if `replayed` is given the
  /// evaluations of an earlier log, keeping its run id and states file (written to a
  /// temporary file and renamed, so the old log survives until the new one is complete).
  /// Without `replayed` a new run id is drawn and an old states file removed.
  /// Throws FileError.
  RunLogWriter(const std::string& path, const RunFingerprint& fingerprint,
               const RunLog* replayed = nullptr);
  ~RunLogWriter();
  RunLogWriter(const RunLogWriter&) = delete;
  RunLogWriter& operator=(const RunLogWriter&) = delete;

  /// Appends one evaluation record and flushes it. Throws FileError.
  void append(const LoggedEvaluation& evaluation);
  /// Rewrites `<path>.states` atomically.
  void write_states(const RunSnapshot& snapshot);

 private:
  void write_record(char kind, const std::string& payload);
  std::string path_;
  std::uint64_t run_id_ = 0;
  std::FILE* file_ = nullptr;
};

}  // namespace softhd

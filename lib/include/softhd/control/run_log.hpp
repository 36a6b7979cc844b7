#pragma once
/// \file run_log.hpp
/// The checkpoint of a shape-tracking run: an append-only binary log of every objective
/// evaluation the optimiser asked for (x, J, ρ̃, A, B, gradient, timings — bitwise), with
/// a fingerprint of the problem up front and, at each accepted iteration, a snapshot of
/// the objective's warm-start states.
///
/// A resumed run starts the optimiser again from the beginning and serves its evaluations
/// from the log (checking that each x matches bitwise) until the log runs out; then the
/// warm-start states are restored and real evaluations continue. For a deterministic
/// optimiser and objective the resumed run is therefore the uninterrupted run, whatever
/// state the optimiser keeps internally.
///
/// File layout: the 8 bytes "SHDLOG01", then records [kind u8][payload length u64]
/// [payload][FNV-1a 64 of kind, length and payload], little-endian doubles stored bitwise.
/// Kinds: 'H' fingerprint text (first record, exactly once), 'E' one evaluation, 'S' a
/// warm-start snapshot. A torn last record (a run killed while writing it) is dropped;
/// anything else malformed is refused.

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

/// One evaluation as the optimiser saw it.
struct LoggedEvaluation {
  Eigen::VectorXd x;
  bool gradient = false;  ///< the optimiser asked for the gradient
  ShapeEvaluation result;
  double seconds = 0.0;  ///< the run's wall time (over all resumes) when it ended
};

/// The objective's warm-start states after a given number of evaluations.
struct RunSnapshot {
  std::int64_t evaluations = 0;  ///< evaluations logged before it
  std::int64_t iterations = 0;   ///< accepted iterations by then
  std::vector<WarmStart> states;
};

/// A checkpoint as read back: the evaluations up to the last snapshot, and that snapshot.
struct RunLog {
  RunFingerprint fingerprint;
  std::vector<LoggedEvaluation> evaluations;
  RunSnapshot snapshot;
  bool has_snapshot = false;
};

/// Parses a log's bytes; `source` names it in errors. Throws FileError (naming the byte
/// offset) for anything but a torn last record.
RunLog parse_run_log(const std::string& bytes, const std::string& source);
/// Reads a log file. Throws FileError (also for a directory or an unreadable file).
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
  /// evaluations and snapshot of an earlier log (written to a temporary file and renamed,
  /// so the old log survives until the new one is complete). Throws FileError.
  RunLogWriter(const std::string& path, const RunFingerprint& fingerprint,
               const RunLog* replayed = nullptr);
  ~RunLogWriter();
  RunLogWriter(const RunLogWriter&) = delete;
  RunLogWriter& operator=(const RunLogWriter&) = delete;

  void append(const LoggedEvaluation& evaluation);
  void append(const RunSnapshot& snapshot);

 private:
  void write_record(char kind, const std::string& payload);
  std::string path_;
  std::FILE* file_ = nullptr;
};

}  // namespace softhd

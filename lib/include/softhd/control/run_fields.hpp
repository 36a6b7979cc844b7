#pragma once
/// \file run_fields.hpp
/// The fields of TrackingRunOptions by their nested path, with the flag of `softhd optimise` and
/// the keyword of Python's `softhd.optimise` that set each one, or why a front end has none.
/// The front ends' tests check their flags and keywords against this table
/// (tests/test_run_fields.cpp, tests/python/test_optimise.py), and the front ends name a field
/// in an error message by their own name for it (name_fields).

#include <string>
#include <vector>

namespace softhd {

struct TrackingRunOptions;

/// One field of TrackingRunOptions and its names on the front ends.
struct RunField {
  const char* path;     ///< e.g. "levels.refined_move_limit"
  const char* flag;     ///< of `softhd optimise`, e.g. "--refined-move-limit"; "": none
  const char* keyword;  ///< of Python's `softhd.optimise`, e.g. "refined_move_limit"; "": none
  const char* why_not;  ///< why a front end has no name for it ("" when both have one)
  /// Copies this field (alone) of `from` into `to`.
  void (*copy)(const TrackingRunOptions& from, TrackingRunOptions& to);
  /// Why the field leaves the checkpoint's fingerprint (TrackingRun::fingerprints) alone: it
  /// does not change the run's path (a limit, an output setting). nullptr: the fingerprint
  /// records it, and a resume with another value is refused (tests/test_run_fields.cpp).
  const char* fingerprint_free = nullptr;
};

/// Every field of TrackingRunOptions, in declaration order; a field that is itself a struct
/// of settings (distance.params, distance.form) by each of its own fields.
const std::vector<RunField>& tracking_run_fields();

/// A flag of `softhd optimise` that sets no field (e.g. "--json"), with what it does.
struct CliOnlyFlag {
  const char* flag;  ///< e.g. "--json"
  const char* what;  ///< what it does
};
/// The flags of `softhd optimise` that are not fields of TrackingRunOptions.
const std::vector<CliOnlyFlag>& optimise_cli_only_flags();

/// The front end an error message is for.
enum class FrontEnd { cli, python };

/// `message` with every field path of tracking_run_fields() in it (a whole word such as
/// "levels.refined_move_limit", not part of a longer one) replaced by that front end's name
/// for the field (its flag or keyword); a path the front end has no name for stays.
std::string name_fields(const std::string& message, FrontEnd front_end);

/// options.validate(), its InvalidArgument naming the field by the front end's name: the paths
/// in the message by name_fields, and a message that names no path (one of the objective's or
/// the optimiser's own checks, e.g. "Hausdorff parameter alpha must be ...") after the name of
/// the first field that is invalid on its own (that field of `options` on the defaults),
/// "--alpha: Hausdorff parameter alpha must be ...".
void validate_naming_fields(const TrackingRunOptions& options, FrontEnd front_end);

}  // namespace softhd

#pragma once
// Command-line plumbing shared by the softhd subcommands: a small argument parser
// whose errors name the option, and the exit-code convention (0 ok, 2 bad input).

#include <optional>
#include <string>
#include <vector>

#include "softhd/error.hpp"

namespace softhd::cli {

/// Bad command-line usage; main() prints it as one line and exits with code 2.
class UsageError : public Error {
 public:
  using Error::Error;
};

/// Options of the form `--name VALUE`, `--name=VALUE` and flags `--name`; every
/// token must be consumed, or finish() reports the first unknown one.
class Args {
 public:
  explicit Args(std::vector<std::string> tokens);

  /// True if `--name` is present (consumed).
  bool flag(const std::string& name);
  /// The value of `--name`, if present (consumed). Throws UsageError if it has none.
  std::optional<std::string> value(const std::string& name);
  /// Every value of a repeatable option, in order.
  std::vector<std::string> values(const std::string& name);
  /// A finite number given to `--name`, or `fallback`.
  double number(const std::string& name, double fallback);
  /// An integer given to `--name`, or `fallback`.
  long integer(const std::string& name, long fallback);
  /// An integer in [lo, hi] given to `--name`, or `fallback`; the error names the range.
  long integer(const std::string& name, long fallback, long lo, long hi);
  /// Throws UsageError "`old_name` is now `new_name`" if `old_name` (or `old_name=...`) is
  /// present: a retired spelling of an option, refused with the one that replaced it.
  void retired(const std::string& old_name, const std::string& new_name) const;
  /// The remaining positional arguments; throws UsageError for an unknown option.
  std::vector<std::string> finish();

 private:
  std::vector<std::string> tokens_;
  std::vector<bool> used_;
};

/// Parses a whole string as a finite double (subnormals included; a nonzero literal that
/// underflows to 0 is refused); `what` names it in the error.
double parse_number(const std::string& text, const std::string& what);

}  // namespace softhd::cli

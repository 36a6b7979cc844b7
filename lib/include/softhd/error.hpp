#pragma once
/// \file error.hpp
/// The one exception family of softhd. Every error a caller can cause (bad input,
/// a malformed file, an invalid parameter) is reported by throwing softhd::Error
/// or a class derived from it, with a message that names the problem.

#include <stdexcept>
#include <string>

namespace softhd {

/// Base of every exception softhd throws.
class Error : public std::runtime_error {
 public:
  /// An exception whose what() is `message` (one line naming the problem).
  explicit Error(const std::string& message) : std::runtime_error(message) {}
};

/// An argument or parameter outside its valid range.
class InvalidArgument : public Error {
 public:
  /// An exception whose what() is `message`.
  using Error::Error;
};

/// A file that cannot be opened, read, parsed or written.
class FileError : public Error {
 public:
  /// An exception whose what() is `message` (names the file, and the line if any).
  using Error::Error;
};

/// A problem larger than the configured limits (memory estimate, index range).
class ResourceError : public Error {
 public:
  using Error::Error;
};

/// A numerical operation that cannot be carried out on valid input (e.g. a solve with a
/// tangent that is not positive definite).
class NumericalError : public Error {
 public:
  using Error::Error;
};

/// A state solve (the equilibrium for a control) that failed on valid input: Newton did not
/// converge within its load steps. The CLI exits 1 for it, as for any NumericalError.
class StateSolveError : public NumericalError {
 public:
  using NumericalError::NumericalError;
};

/// A broken internal invariant: a bug in softhd, not a problem with the input. The message
/// names the invariant and the place; please report it. Thrown by SOFTHD_ASSERT.
class InternalError : public Error {
 public:
  using Error::Error;
};

/// Checks an internal invariant `cond`; if it fails, throws InternalError with `what`, the
/// condition's text and the source position. Always on (the checks are cheap and outside
/// inner loops).
#define SOFTHD_ASSERT(cond, what)                                                                \
  do {                                                                                           \
    if (!(cond))                                                                                 \
      throw ::softhd::InternalError(std::string("internal error (a bug in softhd): ") + (what) + \
                                    " [" #cond "] at " + __FILE__ + ":" +                        \
                                    std::to_string(__LINE__));                                   \
  } while (false)

/// A long call stopped because the interrupt check (softhd/interrupt.hpp) asked it to, e.g.
/// on Ctrl-C in Python (raised there as KeyboardInterrupt).
class Interrupted : public Error {
 public:
  using Error::Error;
};

}  // namespace softhd

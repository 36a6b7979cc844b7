#pragma once
/// \file interrupt.hpp
/// Cancelling long softhd calls: a process-wide check that the long loops poll between
/// units of work, never inside one (between the passes of a distance and between blocks
/// of its outer points, between Newton iterations, between an optimiser's evaluations).
/// When the check returns true the call unwinds with softhd::Interrupted. The Python module
/// installs a check that runs Python's signal handlers, so that Ctrl-C raises
/// KeyboardInterrupt within a fraction of a second; the CLI installs none (SIGINT ends it).

#include <functional>

namespace softhd {

/// Returns true to stop the running softhd call. Called on the thread that made that call,
/// outside any parallel region, a few times per second at most while work goes on.
using InterruptCheck = std::function<bool()>;

/// Installs `check` for every later softhd call of the process (empty: none, the default)
/// and returns the check it replaces. Thread-safe.
InterruptCheck set_interrupt_check(InterruptCheck check);

/// Calls the installed check, if any; throws Interrupted ("interrupted " + `where`) if it
/// returns true. `where` names the loop (e.g. "between distance passes").
void check_interrupt(const char* where);

}  // namespace softhd

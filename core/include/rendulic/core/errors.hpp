// Error types shared by every module (docs/architecture.md "Conventions"). InputError is bad input
// from the user (a file, a scenario key, a value out of range, a non-physical time step, a damaged
// results file, an output folder that cannot be written): the CLI prints its one-line message and
// exits with code 2. Anything else escaping to main is a bug (exit 1).
#pragma once

#include <stdexcept>
#include <string>

namespace rendulic {

inline constexpr int kExitInput = 2;

class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Work stopped on request before it finished (the Python module's Ctrl-C, or its progress
// callback failing; app/progress.hpp): not an error of the input nor a bug. The long loops
// throw it where no parallel region is open.
class Cancelled : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// `text` fit for a one-line message: control characters (a newline, a NUL) shown as \xNN.
std::string printable(const std::string& text);

// One line describing the exception in flight (call inside a catch block): the message of a
// std::exception, the innermost reason of an HDF5 exception (which is not a std::exception),
// or "unknown exception".
std::string describe_current_exception();

// Rethrows the exception in flight (call inside a catch block) with `note` appended to its
// message, keeping its kind: InputError stays InputError (exit 2), anything else becomes
// std::runtime_error (exit 1).
[[noreturn]] void rethrow_with_note(const std::string& note);

// An exception caught where none may leave (a parallel loop, an MPI worker's task), to be
// thrown again after it: its one-line words and whether it was bad input, so that an
// InputError stays one (exit 2) and anything else is an internal error (exit 1).
struct CaughtError {
  std::string message;  // empty: nothing was caught (current() never leaves it empty)
  bool input = false;
  // The exception in flight (call inside a catch block).
  static CaughtError current();
  // Throws it again, of its kind, its words after `prefix`.
  [[noreturn]] void rethrow(const std::string& prefix) const;
};

}  // namespace rendulic

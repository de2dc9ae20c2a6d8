// Error types shared by every module (architecture.md "Errors"). InputError is bad input from
// the user (a file, a scenario key, a value out of range, a non-physical time step): the CLI
// prints its one-line message and exits with code 2. Anything else escaping to main is a bug.
#pragma once

#include <stdexcept>
#include <string>

namespace rendulic {

inline constexpr int kExitInput = 2;

class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A capability whose issue has not landed yet: it says so instead of pretending to work.
class NotAvailable : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace rendulic

// Test support shared by the tests of refusals: the message of the InputError a call throws, so
// that a test can check it names the culprit (docs/usage.md, bad input: one line, exit 2). One
// helper so that every such test fails when the call throws nothing.
#pragma once

#include <gtest/gtest.h>

#include <string>

#include "rendulic/core/errors.hpp"

namespace rendulic::testing {

// The message of the InputError `fn` throws, or "" and a test failure if it throws none.
template <class Fn>
std::string input_error(Fn&& fn) {
  try {
    fn();
  } catch (const InputError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no InputError";
  return "";
}

}  // namespace rendulic::testing

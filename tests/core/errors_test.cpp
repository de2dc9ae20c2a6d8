// The error kinds of core/errors.hpp (docs/architecture.md "Conventions"): an exception caught
// where none may leave (a parallel loop, an MPI worker's task) and thrown again after it keeps
// its kind, so bad input stays exit 2 and anything else is an internal error.
#include "rendulic/core/errors.hpp"

#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

namespace rendulic {
namespace {

template <class Throw>
CaughtError caught(Throw&& thrower) {
  try {
    thrower();
  } catch (...) {
    return CaughtError::current();
  }
  return {};
}

TEST(CaughtError, KeepsTheWordsAndTheKindAcrossTheLoop) {
  const CaughtError input = caught([] { throw InputError("probes.rate: too fast"); });
  EXPECT_EQ(input.message, "probes.rate: too fast");
  EXPECT_TRUE(input.input);
  try {
    input.rethrow("dynamic probe: ");
    ADD_FAILURE() << "not thrown";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "dynamic probe: probes.rate: too fast");
  }
  // Anything else comes back as an internal error, never as bad input.
  for (const CaughtError& other :
       {caught([] { throw std::logic_error("a bug"); }), caught([] { throw 42; })}) {
    EXPECT_FALSE(other.input);
    EXPECT_FALSE(other.message.empty());
    try {
      other.rethrow("state a: ");
      ADD_FAILURE() << "not thrown";
    } catch (const InputError& e) {
      ADD_FAILURE() << "bad input: " << e.what();
    } catch (const std::runtime_error& e) {
      EXPECT_EQ(std::string(e.what()).rfind("state a: ", 0), 0u) << e.what();
    }
  }
  EXPECT_EQ(caught([] { throw std::logic_error("a bug"); }).message, "a bug");
  EXPECT_EQ(caught([] { throw 42; }).message, "unknown exception");
  // An exception without words is still an error after the loop, of its kind.
  const CaughtError wordless = caught([] { throw InputError(""); });
  EXPECT_EQ(wordless.message, "an error without a message");
  EXPECT_TRUE(wordless.input);
  EXPECT_EQ(caught([] { throw std::runtime_error(""); }).message, "an error without a message");
}

}  // namespace
}  // namespace rendulic

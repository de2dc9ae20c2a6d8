// comma_list (core/comma_list.hpp): every list a message, a log line or a report shows is
// written alike, and a long one is cut with a count of the rest.
#include "rendulic/core/comma_list.hpp"

#include <gtest/gtest.h>

#include <array>
#include <string>
#include <string_view>
#include <vector>

namespace rendulic {
namespace {

TEST(CommaList, JoinsAnyRangeOfTexts) {
  EXPECT_EQ(comma_list(std::vector<std::string>{"a", "b", "c"}), "a, b, c");
  EXPECT_EQ(comma_list(std::array<const char*, 2>{"x", "y"}), "x, y");
  EXPECT_EQ(comma_list(std::vector<std::string_view>{"only"}), "only");
}

TEST(CommaList, AnEmptyListIsTheGivenWord) {
  EXPECT_EQ(comma_list(std::vector<std::string>{}), "");
  EXPECT_EQ(comma_list(std::vector<std::string>{}, "(none)"), "(none)");
}

TEST(CommaList, BeyondTheLimitTheRestIsCounted) {
  const std::vector<std::string> v = {"a", "b", "c", "d", "e"};
  EXPECT_EQ(comma_list(v, "", 2), "a, b and 3 more");
  EXPECT_EQ(comma_list(v, "", 2, " (rendulic inspect)"), "a, b and 3 more (rendulic inspect)");
  EXPECT_EQ(comma_list(v, "", 5, " (rendulic inspect)"), "a, b, c, d, e");
}

}  // namespace
}  // namespace rendulic

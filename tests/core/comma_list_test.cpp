// comma_list (core/comma_list.hpp): every list a message, a log line or a report shows is
// written alike, and a long one is cut with a count of the rest; a word outside its choices is
// refused in one wording (not_one_of, choice_refusal).
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

TEST(CommaList, AWordOutsideItsChoicesIsRefusedInOneWording) {
  const std::array<std::string_view, 3> choices = {"auto", "ellipse", "line"};
  EXPECT_EQ(not_one_of("elipse", choices), "'elipse' is not one of auto, ellipse, line");
  EXPECT_EQ(choice_refusal("elipse", choices), not_one_of("elipse", choices));
  for (const auto c : choices) EXPECT_EQ(choice_refusal(c, choices), "") << c;
  // Neither a prefix nor a case variant of a choice is the choice.
  EXPECT_NE(choice_refusal("ell", choices), "");
  EXPECT_NE(choice_refusal("Line", choices), "");
  EXPECT_NE(choice_refusal("", std::vector<std::string>{"a"}), "");
}

}  // namespace
}  // namespace rendulic

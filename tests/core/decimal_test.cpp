// Tests of core/decimal.hpp, the one reading and writing of a number as text
// (docs/architecture.md "Where each concept lives"): against printf and strtod in the C locale
// (an independent implementation of the same text), and in a locale with a decimal comma, which
// a Python session hosting the module may set (locale.setlocale) and under which printf wrote
// "0,66" and strtod stopped at the '.' (model_envelope with a dictionary of parameters was
// refused: "state:3: ... saw ','").
#include "rendulic/core/decimal.hpp"

#include <gtest/gtest.h>

#include <clocale>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <vector>

#include "comma_locale.hpp"
#include "rendulic/core/conventions.hpp"
#include "rendulic/core/result_paths.hpp"
#include "rendulic/core/scenario.hpp"

namespace rendulic {
namespace {

namespace fs = std::filesystem;

std::vector<double> samples() {
  std::vector<double> v = {0.0,       -0.0,
                           0.66,      0.1,
                           1.0 / 3.0, 5e-5,
                           3000.0,    1e-4,
                           1.5e7,     -2.5e-3,
                           123456.0,  1234567.0,
                           1e21,      1e-320,
                           4.9e-324,  1.7976931348623157e308,
                           22.5,      35.26438968275465};
  std::srand(7);
  for (int i = 0; i < 200; ++i) {
    const double m = static_cast<double>(std::rand()) / RAND_MAX - 0.5;
    v.push_back(std::ldexp(m, std::rand() % 200 - 100));
  }
  return v;
}

std::string printf_g(double v, int digits) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*g", digits, v);
  return buf;
}

TEST(Decimal, GIsPrintfsGInTheCLocale) {
  ASSERT_STREQ(std::setlocale(LC_NUMERIC, nullptr), "C");
  for (const double v : samples())
    for (const int digits : {1, 6, 12, 17}) EXPECT_EQ(decimal_g(v, digits), printf_g(v, digits));
  EXPECT_EQ(decimal_g(std::numeric_limits<double>::infinity()), "inf");
  EXPECT_EQ(decimal_g(-std::numeric_limits<double>::infinity()), "-inf");
  EXPECT_EQ(decimal_g(5e-5), "5e-05");
}

TEST(Decimal, FixedIsPrintfsFInTheCLocale) {
  ASSERT_STREQ(std::setlocale(LC_NUMERIC, nullptr), "C");
  char buf[400];
  for (const double v : samples())
    for (const int decimals : {0, 1, 3}) {
      std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
      EXPECT_EQ(decimal_fixed(v, decimals), buf) << v;
    }
  EXPECT_EQ(decimal_fixed(2.45, 1), "2.5");
  EXPECT_EQ(decimal_fixed(59.6, 0), "60");
}

// The shortest %g text that reads back exactly: the loop over precisions with printf and
// strtod (the C locale's) gives the same text.
TEST(Decimal, TextIsTheShortestGThatReadsBackExactly) {
  for (const double v : samples()) {
    std::string expected;
    for (int digits = 6; digits <= 17; ++digits) {
      expected = printf_g(v, digits);
      if (std::strtod(expected.c_str(), nullptr) == v) break;
    }
    const std::string text = decimal_text(v);
    EXPECT_EQ(text, expected);
    ASSERT_TRUE(decimal_number(text).has_value()) << text;
    EXPECT_EQ(*decimal_number(text), v) << text;
  }
  EXPECT_EQ(toml_number(3000.0), "3000.0");
  EXPECT_EQ(toml_number(0.1), "0.1");
  EXPECT_EQ(toml_number(std::numeric_limits<double>::infinity()), "inf");
}

TEST(Decimal, RefusalsNameTheTextInTheSameWords) {
  for (const std::string bad :
       {"", " 1", "1 ", "0x10", "nan", "inf", "1e400", "1,5", "1.5.", "--1"})
    EXPECT_FALSE(decimal_number(bad).has_value()) << bad;
  EXPECT_EQ(decimal_number("+4"), 4.0);
  EXPECT_EQ(decimal_number("1e-400"), 0.0);
  EXPECT_EQ(not_a_decimal_number("1,5\x01"), "'1,5\\x01' is not a finite decimal number");
}

TEST_F(CommaLocale, NumbersAreReadAndWrittenWithAPoint) {
  EXPECT_EQ(decimal_number("1.5"), 1.5);
  EXPECT_EQ(decimal_number("-2.5e-3"), -2.5e-3);
  EXPECT_FALSE(decimal_number("1,5").has_value());
  EXPECT_EQ(decimal_g(0.66), "0.66");
  EXPECT_EQ(decimal_fixed(2.5, 1), "2.5");
  EXPECT_EQ(decimal_text(0.1), "0.1");
  EXPECT_EQ(decimal_text(1.0 / 3.0), "0.3333333333333333");
  EXPECT_EQ(toml_number(2.5), "2.5");
  // Names of groups and probe planes are those every other process writes and reads.
  EXPECT_EQ(paths::group_number(0.66), "0.66");
  EXPECT_EQ(paths::envelope_name("dynamic", 5e-5), "dynamic_5e-05");
  EXPECT_EQ(meridian_plane(22.5).name, "meridian_22.5");
  ASSERT_TRUE(probe_plane_named("meridian_22.5").has_value());
  EXPECT_EQ(probe_plane_named("meridian_22.5")->name, "meridian_22.5");
}

}  // namespace
}  // namespace rendulic

// What the progress observer (the Python module's callback, app/progress.hpp; docs/python.md)
// is told: the stage at once, the first report of every task however soon it comes, and then
// at most one report per kObserveEvery seconds. Before, a task shorter than kObserveEvery (the
// dynamic probes of a small state took 0.19 s on a Zen 5 host) never reached the callback, and
// a callback waiting for it could not stop the work. No timing is asserted: every report here
// comes well within kObserveEvery of the one before.
#include "progress.hpp"

#include <gtest/gtest.h>

#include <limits>
#include <string>
#include <tuple>
#include <vector>

#include "comma_locale.hpp"

namespace rendulic::app {
namespace {

using Report = std::tuple<std::string, std::string, double>;

class ProgressObserverTest : public ::testing::Test {
 protected:
  void SetUp() override {
    set_progress_observer([this](const std::string& stage, const std::string& task, double f) {
      seen.emplace_back(stage, task, f);
    });
  }
  void TearDown() override { set_progress_observer({}); }
  std::vector<Report> seen;
};

TEST_F(ProgressObserverTest, EveryTaskIsSeenAtItsFirstReportAndTheRestIsPaced) {
  RunContext ctx;
  ctx.quiet = true;
  Progress progress(ctx, "probes");
  ASSERT_EQ(seen.size(), 1u);
  EXPECT_EQ(seen.back(), Report("probes", "", 0.0));
  progress.start_task("dynamic");
  progress.count(1, 8);
  ASSERT_EQ(seen.size(), 2u);
  EXPECT_EQ(seen.back(), Report("probes", "dynamic", 0.125));
  progress.count(2, 8);  // the same task, at once: paced
  EXPECT_EQ(seen.size(), 2u);
  progress.start_task("minimisation");
  progress(0.5);
  ASSERT_EQ(seen.size(), 3u);
  EXPECT_EQ(seen.back(), Report("probes", "minimisation", 0.5));
  progress(0.75);
  EXPECT_EQ(seen.size(), 3u);
}

// A stage of decades (preparation.rate = 1e-3 instead of 1e3) said "about ? left" at 0.0 % for
// as long as anyone watched; and 1e14 s of hours overflowed an int.
TEST(Progress, TimeLeftIsKnownAfterAFewSecondsHoweverLittleIsDone) {
  EXPECT_EQ(time_left(0.0, 100.0), "?");
  EXPECT_EQ(time_left(1e-4, kPaceAfter / 2), "?");  // too early to say
  EXPECT_EQ(time_left(0.5, 10.0), "10 s");
  EXPECT_EQ(time_left(1e-8, 14.0), "44.4 years");
  EXPECT_EQ(time_left(1.0, 3.0), "0 s");
  EXPECT_EQ(human_seconds(3725.0), "1 h 02 min");
  EXPECT_EQ(human_seconds(47 * 3600.0), "47 h 00 min");
  EXPECT_EQ(human_seconds(3 * 86400.0), "3 days");
  EXPECT_EQ(human_seconds(1e14), "3.17e+06 years");
  EXPECT_EQ(human_seconds(std::numeric_limits<double>::infinity()), "?");
}

TEST(Progress, ThePercentageIsFiveCharactersWide) {
  EXPECT_EQ(percent_done(0.0), "  0.0%");
  EXPECT_EQ(percent_done(0.025), "  2.5%");
  EXPECT_EQ(percent_done(0.5), " 50.0%");
  EXPECT_EQ(percent_done(1.0), "100.0%");
  EXPECT_EQ(percent_done(2.0), "100.0%");
}

// A Python session that set a locale with a decimal comma had its progress lines read
// "  2,5%" and "3,17e+06 years" (printf follows the process's locale).
using ProgressInACommaLocale = CommaLocale;
TEST_F(ProgressInACommaLocale, NumbersKeepTheirPoint) {
  EXPECT_EQ(percent_done(0.025), "  2.5%");
  EXPECT_EQ(human_seconds(1e14), "3.17e+06 years");
  EXPECT_EQ(human_seconds(12.4), "12 s");
}

}  // namespace
}  // namespace rendulic::app

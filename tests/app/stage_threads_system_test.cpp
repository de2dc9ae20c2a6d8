// bench/stage_threads.py, the measurement of issue #13's thread criteria per stage
// (docs/performance.md "The stages, default against one thread, in one command"), run on the
// tiny scenario's first two stages: every stage timed for both settings in both conditions, the
// order of the settings swapped each round, the runs kept where asked, and a wrong argument or
// a failing run refused in one line with exit 2. Nothing here judges a time.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "cli_runner.hpp"
#include "tiny_run.hpp"

namespace fs = std::filesystem;
using rendulic::testing::CliResult;
using rendulic::testing::fresh_dir;
using rendulic::testing::read_file;
using rendulic::testing::run_command;
using rendulic::testing::tiny_scenario;

namespace {

const fs::path kScript = fs::path(RENDULIC_SOURCE_DIR) / "bench" / "stage_threads.py";

CliResult stage_threads(const std::string& args, bool merge = false) {
  return run_command("/usr/bin/python3 " + kScript.string() + " " + RENDULIC_EXE + " " + args,
                     merge);
}

int count(const std::string& text, const std::string& what) {
  int n = 0;
  for (auto at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

// How many processes have `what` in their command line (/proc/PID/cmdline, arguments separated
// by NULs, read as spaces), read from /proc itself: the base image has no `ps`.
int processes_naming(const std::string& what) {
  int n = 0;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator("/proc", ec)) {
    std::string cmdline = read_file(e.path() / "cmdline");
    for (char& c : cmdline)
      if (c == '\0') c = ' ';
    n += cmdline.find(what) != std::string::npos ? 1 : 0;
  }
  return n;
}

}  // namespace

TEST(StageThreads, TimesEveryStageForBothSettingsIdleAndLoadedInAlternatedRounds) {
  const fs::path dir = fresh_dir("stage_threads");
  const fs::path scenario = tiny_scenario(dir), runs = dir / "runs", json = dir / "rows.json";
  const CliResult r = stage_threads("--scenario " + scenario.string() +
                                    " --stages prepare,isotropic --rounds 2 --out " +
                                    runs.string() + " --json " + json.string());
  ASSERT_EQ(r.code, 0) << r.out << r.err;
  // Every run kept, each with its stages' timings.
  for (const char* round : {"r0", "r1"})
    for (const char* cond : {"idle", "loaded"})
      for (const char* setting : {"default", "one"})
        EXPECT_TRUE(
            fs::exists(runs / (std::string(round) + "-" + cond + "-" + setting) / "results.h5"))
            << round << cond << setting;
  // The settings' order swapped in the second round, in both conditions.
  const std::string& log = r.err;
  for (const char* cond : {"idle  ", "loaded"}) {
    const auto d1 = log.find(std::string("round 1/2 ") + cond + " default");
    const auto o1 = log.find(std::string("round 1/2 ") + cond + " one thread");
    const auto d2 = log.find(std::string("round 2/2 ") + cond + " default");
    const auto o2 = log.find(std::string("round 2/2 ") + cond + " one thread");
    ASSERT_NE(d1, std::string::npos) << log;
    ASSERT_NE(o1, std::string::npos) << log;
    ASSERT_NE(d2, std::string::npos) << log;
    ASSERT_NE(o2, std::string::npos) << log;
    EXPECT_LT(d1, o1) << log;
    EXPECT_LT(o2, d2) << log;
  }
  // A row per stage and the sum in each condition, two times per setting in each, both
  // verdicts.
  const std::string rows = read_file(json);
  for (const char* stage : {"\"prepare\"", "\"isotropic\"", "\"(sum)\""})
    EXPECT_EQ(count(rows, "\"stage\": " + std::string(stage)), 2) << rows;
  EXPECT_EQ(count(rows, "\"stage\": "), 6) << rows;
  EXPECT_EQ(count(rows, "\"condition\": \"loaded\""), 3) << rows;
  EXPECT_EQ(count(rows, "\"ratio_median\": null"), 0) << rows;
  EXPECT_NE(r.out.find("idle: prepare, isotropic together"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("loaded: worst stage"), std::string::npos) << r.out;
  // No busy loop outlives the script (each is named after the runs' folder in its arguments).
  EXPECT_EQ(processes_naming("rendulic-busy " + runs.string()), 0);
}

TEST(StageThreads, RefusesAWrongArgumentOrAFailingRunInOneLine) {
  const fs::path dir = fresh_dir("stage_threads_refusals");
  const fs::path scenario = tiny_scenario(dir);
  const auto refused = [](const CliResult& r, const std::string& culprit) {
    EXPECT_EQ(r.code, 2) << r.out;
    EXPECT_EQ(count(r.out, "\n"), 1) << r.out;
    EXPECT_NE(r.out.find(culprit), std::string::npos) << r.out;
  };
  refused(stage_threads("--scenario " + (dir / "none.toml").string(), true), "none.toml");
  refused(stage_threads("--scenario " + scenario.string() + " --rounds 0", true), "--rounds");
  refused(stage_threads("--scenario " + scenario.string() + " --roundz 2", true), "--roundz");
  // The binary's own refusal of a stage it does not know, passed on.
  refused(stage_threads("--scenario " + scenario.string() + " --stages prepare,isotropc --out " +
                            (dir / "runs").string(),
                        true),
          "isotropc");
}

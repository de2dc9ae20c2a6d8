// System test of `rendulic sweep --quick`: the real binary sweeps the quick
// scenario's first state (N 250/500, 8 directions, about 15 s on one core) and writes
// sweep.h5, sweep.csv and the Pareto chart. Checked on the file's own numbers: the linear
// response, the elastic reference, has zero error against itself, the minimisation probes (an
// independent method) agree with it, the dynamic error falls as the relaxation threshold
// tightens, a time step beyond the stability bound is reported as refused with no numbers;
// bad input exits 2 with one line and writes nothing.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "cli_runner.hpp"
#include "rendulic/core/results.hpp"

namespace {
namespace fs = std::filesystem;
using rendulic::ResultsReader;
using rendulic::testing::fresh_dir;
using rendulic::testing::run_rendulic;

const std::string kQuick = std::string(RENDULIC_SOURCE_DIR) + "/data/scenarios/quick.toml";

// Every point group of the file.
std::vector<std::string> points(const ResultsReader& f) {
  std::vector<std::string> out;
  for (const auto& name : f.children("/sweep/points")) out.push_back("/sweep/points/" + name);
  return out;
}

void expect_reference_exact_and_minimisation_close(const ResultsReader& f) {
  int checked = 0;
  for (const auto& g : points(f)) {
    if (f.attr_string(g, "envelope") != "elastic" || f.attr_string(g, "factor") != "method")
      continue;
    const std::string method = f.attr_string(g, "method");
    ASSERT_EQ(f.attr_string(g, "status"), "ok") << g;
    // The reference against itself: the same numbers, so zero up to round-off.
    if (method == "linear_response") {
      EXPECT_LT(f.attr_double(g, "error"), 1e-12);
      ++checked;
    }
    // FIRE to 1e-9 of the mean contact force is the quasi-static limit of the same
    // mechanics: measured 1e-4..1e-2 of a_ref (a 5e-5 probe opens or closes a contact now and
    // then, which the linear response by definition never does).
    if (method == "minimisation") {
      EXPECT_LT(f.attr_double(g, "error"), 0.03);
      ++checked;
    }
  }
  EXPECT_EQ(checked, 2);
}

void expect_error_falls_as_relaxation_tightens(const ResultsReader& f) {
  std::map<double, double> error;  // threshold -> error
  for (const auto& g : points(f))
    if (f.attr_string(g, "factor") == "relax") {
      ASSERT_EQ(f.attr_string(g, "status"), "ok") << g;
      error[f.attr_double(g, "value")] = f.attr_double(g, "error");
    }
  ASSERT_GE(error.size(), 3u);
  // The relaxation is not monotone in between: a loose threshold stops at the first check
  // after the relaxation peak, and at N = 250 the error even rose from 1e-6 to 1e-7 in one
  // measured run (0.11 -> 0.15, then 0.033 at 1e-8). What must hold: the tightest threshold
  // is the most accurate, within the scatter of a converged envelope (10 % or 0.03 a_ref: over
  // seeds 1-4 the error at 1e-8 ranged from 0.019 to 0.051 a_ref, and in one run it exceeded
  // that at 1e-7 by 0.019; a round-off change of the force sums draws another realization).
  const double tightest = error.begin()->second;
  for (auto it = std::next(error.begin()); it != error.end(); ++it)
    EXPECT_LE(tightest, std::max(1.1 * it->second, it->second + 0.03))
        << "threshold " << error.begin()->first << " vs " << it->first;
  // And it is no worse than the loosest. (It used to fall by half and more: the probed state
  // was only relaxed dynamically, and a loose threshold stopped while the state itself still
  // moved. The state is now at rest, dem.md "States at rest", and every threshold from 1e-4
  // to 1e-7 stops at the same first check after the relaxation peak.)
  EXPECT_LE(error.begin()->second, error.rbegin()->second);
}

void expect_unstable_step_refused(const ResultsReader& f) {
  const double bound = f.attr_double("/sweep", "stability_limit_factor");
  int refused = 0, accepted = 0;
  for (const auto& g : points(f)) {
    if (f.attr_string(g, "factor") != "dt_factor") continue;
    const double v = f.attr_double(g, "value");
    const std::string status = f.attr_string(g, "status");
    if (v >= bound) {
      EXPECT_EQ(status, "refused") << g;
      EXPECT_NE(f.attr_string(g, "note").find("beyond stability"), std::string::npos);
      EXPECT_FALSE(f.has_attr(g, "error")) << "a refused point must carry no error";
      ++refused;
    } else {
      // Below the bound the scheme runs: an envelope with a finite error, or (were the bound
      // not sufficient for this packing) a point marked diverged, again without numbers.
      EXPECT_TRUE(status == "ok" || status == "diverged") << g << ": " << status;
      if (status == "ok") {
        EXPECT_TRUE(std::isfinite(f.attr_double(g, "error"))) << g;
      } else {
        EXPECT_FALSE(f.has_attr(g, "error")) << g;
      }
      ++accepted;
    }
  }
  EXPECT_GE(refused, 1);
  EXPECT_GE(accepted, 2);
  bool said_refused = false;
  for (const std::string& line : f.attr_strings("/sweep", "breaks"))
    said_refused = said_refused || line.find("refused") != std::string::npos;
  EXPECT_TRUE(said_refused);
}

// One run serves every check (ctest runs each TEST in its own process).
TEST(Sweep, QuickRunWritesFilesAndItsNumbersHold) {
  const fs::path dir = fresh_dir("app_sweep_quick");
  // One thread: on a shared machine a 2-thread team waits at every barrier of the engine.
  const auto r =
      run_rendulic("sweep " + kQuick + " --quick --threads 1 --quiet --out " + dir.string());
  ASSERT_EQ(r.code, 0) << r.out;
  for (const char* name : {"sweep.h5", "sweep.csv", "pareto.png", "pareto.svg"}) {
    const fs::path p = dir / name;
    ASSERT_TRUE(fs::exists(p)) << p;
    EXPECT_GT(fs::file_size(p), 500u) << p;
  }
  for (const auto& e : fs::directory_iterator(dir))
    EXPECT_EQ(e.path().string().find(".tmp"), std::string::npos) << e.path();
  const ResultsReader f(dir / "sweep.h5");
  {
    SCOPED_TRACE("linear response and minimisation");
    expect_reference_exact_and_minimisation_close(f);
  }
  {
    SCOPED_TRACE("relaxation threshold");
    expect_error_falls_as_relaxation_tightens(f);
  }
  {
    SCOPED_TRACE("time step");
    expect_unstable_step_refused(f);
  }
}

TEST(Sweep, BadInputExitsTwoWithOneLineAndWritesNothing) {
  const fs::path root = fresh_dir("app_sweep_bad");
  int k = 0;
  // The option is named: "sweep: target must be in (0, 1)" and "sweep: unknown factor" were
  // the options struct's words.
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"--factors bogus",
       "--factors: 'bogus' is not one of dt_factor, n_particles, inertial_number, relax, "
       "dt_factor_tight, method, path_rate"},
      {"--target 2", "--target: Value 2 is out of range (0, 1)"},
      {"--target 0", "--target: Value 0 is out of range (0, 1)"},
      {"--set dem.dt_factor=0.5", "dem.dt_factor"},
      {"--set probes.amplitudes=[0.002]", "probes.amplitudes"},
      {"--set no.such_key=1", "no.such_key"},
      {"--threads -1", "--threads: Value -1 is out of range [0, 4096]"},
      // Beyond path.rate's range: it ran, 'ok', with an inertial number of inf.
      {"--factors path_rate --path-rates 1e308", "path.rate"}};
  for (const auto& [args, says] : cases) {
    const fs::path out = root / ("o" + std::to_string(k++));
    const auto r = run_rendulic("sweep " + kQuick + " --quick --out " + out.string() + " " + args);
    EXPECT_EQ(r.code, 2) << args << ": " << r.out;
    EXPECT_EQ(std::count(r.out.begin(), r.out.end(), '\n'), 1) << args << ": " << r.out;
    EXPECT_NE(r.out.find(says), std::string::npos) << args << ": " << r.out;
    EXPECT_FALSE(fs::exists(out)) << args;
  }
  const auto r =
      run_rendulic("sweep /no/such/scenario.toml --quick --out " + (root / "x").string());
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_FALSE(fs::exists(root / "x"));
  // Outputs that cannot be put in place are refused before the sweep, not after every point
  // has run; an empty --out wrote into the current folder.
  fs::create_directories(root / "csv" / "sweep.csv");
  const auto csv = run_rendulic("sweep " + kQuick + " --quick --factors path_rate --out " +
                                (root / "csv").string());
  EXPECT_EQ(csv.code, 2) << csv.out;
  EXPECT_NE(csv.out.find("sweep.csv: is a folder"), std::string::npos) << csv.out;
  EXPECT_FALSE(fs::exists(root / "csv" / "sweep.h5"));
  const auto empty = run_rendulic("sweep " + kQuick + " --quick --out ''");
  EXPECT_EQ(empty.code, 2) << empty.out;
  EXPECT_NE(empty.out.find("--out: the output folder name is empty (. for the current folder)"),
            std::string::npos)
      << empty.out;
}

}  // namespace

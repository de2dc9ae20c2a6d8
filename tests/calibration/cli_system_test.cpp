// `rendulic calibrate` end to end (docs/calibration.md): a results file built here with
// ResultsWriter from model-generated envelopes (the layout another DEM code would convert to),
// the JSON keys users rely on, /calibration/<model> written back, exit code 2 with the file
// untouched (byte for byte, no temporary left behind) on bad input.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "rendulic/core/results.hpp"
#include "synthetic.hpp"
#include "synthetic_file.hpp"

namespace rendulic::calibration {
namespace {

namespace fs = std::filesystem;

const double kKStar = 5e10;  // Pa: k / (2 <r>) of docs/physics.md

// Each test's file in a folder of its own: ctest runs the tests of this file in parallel, and
// one test's check of "no temporary left" must not see another's file being written.
fs::path make_results_file(const std::string& name) {
  const fs::path dir = fs::path(RENDULIC_TEST_TMP) / "calibration_cli" / fs::path(name).stem();
  fs::create_directories(dir);
  const fs::path file = dir / name;
  const auto law = testing::law_with("anisotropic_elastic",
                                     {{"B", 2.2e10}, {"G", 3e9}, {"beta_A", 0.8}, {"c_F", 4.0}});
  testing::SyntheticSpec spec;
  spec.noise = {0.002, 9};
  const CalibrationData d = testing::synthetic_data(*law, spec);
  ResultsWriter w(file);
  testing::write_results(w, d, kKStar);
  w.create_group("/states/no_envelopes");
  w.write("/states/no_envelopes/stress", Eigen::Matrix3d(Eigen::Matrix3d::Identity() * 1e9));
  w.commit();
  return file;
}

int run(const std::string& args, const fs::path& out) {
  const std::string cmd =
      std::string(RENDULIC_EXE) + " calibrate " + args + " > " + out.string() + " 2>&1";
  const int rc = std::system(cmd.c_str());
  return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

std::string slurp(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

TEST(CalibrateCli, WritesJsonAndCalibrationGroup) {
  const fs::path file = make_results_file("ok.h5");
  const fs::path json = file.parent_path() / "ok.json";
  const fs::path log = file.parent_path() / "ok.log";
  ASSERT_EQ(run("--results " + file.string() +
                    " --model anisotropic_elastic --states s0,s1,s3 "
                    "--holdout s2 --out " +
                    json.string(),
                log),
            0)
      << slurp(log);
  const std::string j = slurp(json);
  for (const char* key : {"\"model\": \"anisotropic_elastic\"", "\"params\"", "\"stderr\"",
                          "\"correlation\"", "\"per_state\"", "\"s0\"", "\"s2\"", "\"B\"", "\"G\"",
                          "\"A\"", "\"held_out_misfit\"", "\"converged\": true"})
    EXPECT_NE(j.find(key), std::string::npos) << key << "\n" << j;
  EXPECT_EQ(j.find("nan"), std::string::npos);
  const ResultsReader r(file);
  EXPECT_TRUE(r.exists("/calibration/anisotropic_elastic/params"));
  EXPECT_TRUE(r.exists("/calibration/anisotropic_elastic/stderr"));
  EXPECT_TRUE(r.exists("/calibration/anisotropic_elastic/correlation"));
  EXPECT_TRUE(r.exists("/calibration/anisotropic_elastic/states/s2/envelopes/elastic/stress_star"));
  EXPECT_EQ(r.attr_int("/calibration/anisotropic_elastic", "converged"), 1);
  EXPECT_GE(r.attr_double("/calibration/anisotropic_elastic", "objective"), 0.0);
  // B recovered from 0.2% noise: well within 1%.
  const auto p = r.read_vector("/calibration/anisotropic_elastic/params");
  EXPECT_NEAR(p[0] / 2.2e10, 1.0, 1e-2);
  // The original data are still there.
  EXPECT_TRUE(r.exists("/states/s0/envelopes/elastic/stress_star"));
}

TEST(CalibrateCli, BadInputExitsTwoAndLeavesTheFileUntouched) {
  const fs::path file = make_results_file("bad.h5");
  const std::string before = slurp(file);
  const fs::path log = file.parent_path() / "bad.log";
  EXPECT_EQ(run("--results " + file.string() + " --model no_such_law", log), 2);
  EXPECT_NE(slurp(log).find("no_such_law"), std::string::npos);
  EXPECT_EQ(run("--results " + file.string() + " --model anisotropic_elastic --states s0,zz", log),
            2);
  EXPECT_NE(slurp(log).find("zz"), std::string::npos);
  EXPECT_EQ(
      run("--results " + file.string() + " --model anisotropic_elastic --states no_envelopes", log),
      2);
  EXPECT_NE(slurp(log).find("no envelopes"), std::string::npos);
  EXPECT_EQ(run("--results " + file.string() + " --model anisotropic_elastic --free B,nope", log),
            2);
  // A name or label that is not there comes with those that are.
  EXPECT_NE(slurp(log).find("unknown parameter 'nope' of anisotropic_elastic (known: B, "),
            std::string::npos)
      << slurp(log);
  EXPECT_EQ(run("--results " + file.string() + " --model anisotropic_elastic --holdout zz", log),
            2);
  EXPECT_NE(slurp(log).find("held-out state 'zz' is not in the data (states: s0, "),
            std::string::npos)
      << slurp(log);
  // An empty list ("--states \"$S\"" with S unset) calibrated with the option's default.
  for (const char* option : {"--states", "--holdout", "--free", "--value"}) {
    EXPECT_EQ(
        run("--results " + file.string() + " --model anisotropic_elastic " + option + " ''", log),
        2)
        << option;
    EXPECT_NE(slurp(log).find(std::string(option) +
                              ": the list is empty (leave the option out for its default)"),
              std::string::npos)
        << slurp(log);
  }
  for (const char* value : {"B", "=3"}) {
    EXPECT_EQ(
        run("--results " + file.string() + " --model anisotropic_elastic --value " + value, log),
        2);
    EXPECT_NE(slurp(log).find("--value '" + std::string(value) + "': expected name=number"),
              std::string::npos)
        << slurp(log);
  }
  const fs::path text = file.parent_path() / "not_hdf5.h5";
  std::ofstream(text) << "hello";
  EXPECT_EQ(run("--results " + text.string() + " --model anisotropic_elastic", log), 2);
  EXPECT_EQ(slurp(file), before);
  for (const auto& e : fs::directory_iterator(file.parent_path()))
    EXPECT_EQ(e.path().filename().string().find(".tmp"), std::string::npos) << e.path();
}

namespace rendulic::calibration {
namespace {

// The `calibration` run stage reads the run's own file while the writer still holds it open
// (before commit); HDF5 shares the open file within the process, so the loader sees it all.
TEST(CalibrateCli, LoaderReadsAFileStillBeingWritten) {
  const fs::path dir = fs::path(RENDULIC_TEST_TMP) / "calibration_cli";
  fs::create_directories(dir);
  const fs::path src = make_results_file("open_src.h5");
  const ResultsReader r(src);
  ResultsWriter w(dir / "open.h5");
  w.attr("/material", "k_star", kKStar);
  for (const auto& l : r.children("/states")) {
    const std::string g = "/states/" + l;
    w.write(g + "/stress", r.read_tensor(g + "/stress"));
    w.write(g + "/fabric", r.exists(g + "/fabric") ? r.read_tensor(g + "/fabric")
                                                   : Eigen::Matrix3d(Eigen::Matrix3d::Zero()));
    if (!r.exists(g + "/envelopes")) continue;
    for (const auto& e : r.children(g + "/envelopes")) {
      const std::string eg = g + "/envelopes/" + e;
      w.attr(eg, "amplitude", r.attr_double(eg, "amplitude"));
      w.write(eg + "/theta_deg", r.read_vector(eg + "/theta_deg"));
      w.write(eg + "/strain", r.read_pairs(eg + "/strain"));
      w.write(eg + "/stress_star", r.read_pairs(eg + "/stress_star"));
      w.write(eg + "/fabric", r.read_pairs(eg + "/fabric"));
    }
  }
  const CalibrationData d = load_calibration_data(w.temporary_path());
  EXPECT_EQ(d.states.size(), 4u);
  EXPECT_EQ(d.states[0].envelopes[0].name, "elastic");
  EXPECT_EQ(d.states[0].envelopes[0].method, "unknown");  // the file names none
  EXPECT_NEAR(d.states[0].envelopes[0].stress[3].norm() /
                  (r.read_pairs("/states/s0/envelopes/elastic/stress_star")[3].norm() * kKStar),
              1.0, 1e-12);
}

}  // namespace
}  // namespace rendulic::calibration

// The stopping rule is the user's: an iteration budget that is reached is reported as "not
// converged" (never passed off as a fit), and a tolerance outside its range is refused.
TEST(CalibrateCli, IterationBudgetAndToleranceAreHonoured) {
  const fs::path file = make_results_file("budget.h5");
  const fs::path json = file.parent_path() / "budget.json";
  const fs::path log = file.parent_path() / "budget.log";
  ASSERT_EQ(run("--results " + file.string() +
                    " --model anisotropic_elastic --no-write --max-iterations 1 "
                    "--function-tolerance 1e-15 --out " +
                    json.string(),
                log),
            0)
      << slurp(log);
  EXPECT_NE(slurp(json).find("\"converged\": false"), std::string::npos) << slurp(json);
  EXPECT_NE(slurp(log).find("did not report convergence"), std::string::npos) << slurp(log);
  ASSERT_EQ(run("--results " + file.string() + " --model anisotropic_elastic --no-write --out " +
                    json.string(),
                log),
            0)
      << slurp(log);
  EXPECT_NE(slurp(json).find("\"converged\": true"), std::string::npos) << slurp(json);
  EXPECT_NE(run("--results " + file.string() +
                    " --model anisotropic_elastic --no-write --function-tolerance 0.5",
                log),
            0);
  EXPECT_NE(slurp(log).find("--function-tolerance"), std::string::npos) << slurp(log);
}

}  // namespace
}  // namespace rendulic::calibration

// `rendulic calibrate --model umat --umat PATH.so --params P.toml` end to end (docs/umat.md
// "Calibration"): the Fortran linear elastic UMAT calibrated against elastic envelopes made by
// the built-in isotropic_elastic law recovers its K and G (free by name and by PROPS index),
// reports standard errors, and is stored under /calibration/umat beside the model selection;
// a UMAT without --umat, a PROPS index out of range and a free prop without bounds exit 2 with
// one line.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "cli_runner.hpp"
#include "rendulic/core/results.hpp"
#include "synthetic.hpp"
#include "synthetic_file.hpp"

namespace rendulic::calibration {
namespace {

namespace fs = std::filesystem;
using rendulic::testing::error_lines;
using rendulic::testing::fresh_dir;
using rendulic::testing::run_rendulic;

constexpr double kKStar = 5e10;
constexpr double kK = 1.8e10, kG = 3.2e9;

fs::path make_results_file(const fs::path& dir) {
  const fs::path file = dir / "results.h5";
  const auto law = testing::law_with("isotropic_elastic", {{"K", kK}, {"G", kG}});
  const CalibrationData d = testing::synthetic_data(*law, {});
  ResultsWriter w(file);
  testing::write_results(w, d, kKStar);
  w.commit();
  return file;
}

std::string lib() { return std::string(RENDULIC_UMAT_DIR) + "/linear_elastic.so"; }
std::string params() {
  return std::string(RENDULIC_SOURCE_DIR) + "/data/umat/linear_elastic_params.toml";
}

TEST(UmatCalibrateCli, LinearElasticUmatRecoversKAndG) {
  if (!fs::exists(lib())) GTEST_SKIP() << "no Fortran compiler: " << lib();
  const fs::path dir = fresh_dir("calibration_umat_cli_recover");
  const fs::path file = make_results_file(dir);
  const auto r = run_rendulic("calibrate --results " + file.string() + " --model umat --umat " +
                                  lib() + " --params " + params() + " --free 1,G --holdout none",
                              false);
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j.at("model"), "umat");
  const auto& p = j.at("params");
  EXPECT_NEAR(p.at("K").get<double>() / kK, 1.0, 1e-6) << r.out;
  EXPECT_NEAR(p.at("G").get<double>() / kG, 1.0, 1e-6) << r.out;
  EXPECT_TRUE(j.at("stderr").at("K").is_number()) << r.out;
  const ResultsReader in(file);
  EXPECT_TRUE(in.exists("/calibration/umat"));
}

TEST(UmatCalibrateCli, BadUmatInputExitsTwoWithOneLine) {
  if (!fs::exists(lib())) GTEST_SKIP();
  const fs::path dir = fresh_dir("calibration_umat_cli_bad");
  const fs::path file = make_results_file(dir);
  std::ofstream(dir / "no_bounds.toml") << "props = [2e10, 2.5e9]\nprop_names = [\"K\", \"G\"]\n";
  const std::string base = "calibrate --no-write --results " + file.string() + " --model umat";
  const struct {
    std::string args, culprit;
  } cases[] = {
      {base + " --params " + params(), "--umat"},
      {base + " --umat " + lib() + " --params " + params() + " --free 3", "--free 3"},
      // Beyond an unsigned long: "internal error: stoul", exit 1.
      {base + " --umat " + lib() + " --params " + params() + " --free 99999999999999999999999",
       "--free 99999999999999999999999: the UMAT has PROPS(1..2)"},
      {base + " --umat " + lib() + " --params " + (dir / "no_bounds.toml").string(),
       "no free props"},
      {"calibrate --no-write --results " + file.string() + " --model isotropic_elastic --umat " +
           lib(),
       "goes with model umat"},
  };
  for (const auto& c : cases) {
    const auto r = run_rendulic(c.args, false);
    EXPECT_EQ(r.code, 2) << c.args << "\n" << r.err;
    EXPECT_EQ(error_lines(r.err), 1) << r.err;
    EXPECT_NE(r.err.find(c.culprit), std::string::npos) << r.err;
  }
}

// The calibration stage is checked before the DEM runs: model umat without its library, or
// with a library that is not there, stops `rendulic run` at once with one line.
TEST(UmatCalibrateCli, RunRefusesAMissingUmatBeforeTheDem) {
  const fs::path dir = fresh_dir("calibration_umat_cli_run");
  const std::string run = "run " + std::string(RENDULIC_SOURCE_DIR) +
                          "/data/scenarios/quick.toml --out " + dir.string() +
                          " --set calibration.model=umat";
  const struct {
    std::string args, culprit;
  } cases[] = {
      {run, "calibration.umat"},
      {run + " --set calibration.umat=" + (dir / "missing.so").string() +
           " --set calibration.umat_params=" + params(),
       "missing.so: no such file"},
  };
  for (const auto& c : cases) {
    const auto r = run_rendulic(c.args, false);
    EXPECT_EQ(r.code, 2) << c.args << "\n" << r.err;
    EXPECT_EQ(error_lines(r.err), 1) << r.err;
    EXPECT_NE(r.err.find(c.culprit), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(dir / "results.h5"));
  }
}

}  // namespace
}  // namespace rendulic::calibration

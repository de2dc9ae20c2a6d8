// The calibrated laws beside the DEM, end to end (docs/calibration.md "Model envelopes beside
// the DEM"): a results file built here (elasto-plastic envelopes and the undrained path of a
// known law, in the layout of results.md), `rendulic calibrate` for three laws (one without
// fabric) with the default held-out states, then `rendulic plot` and `rendulic report`: the
// overlay figures exist, each names every calibrated law it draws (its SVG description; the
// law without fabric is named as such in the fabric figures), and the report has its "Model
// selection" section with the selected law in its table.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "rendulic/core/results.hpp"
#include "synthetic.hpp"

namespace rendulic::calibration {
namespace {

namespace fs = std::filesystem;

const double kKStar = 5e10;

fs::path make_file(const fs::path& dir) {
  fs::remove_all(dir);
  fs::create_directories(dir);
  const auto law = testing::law_with("elastoplastic_fabric", {{"B", 2.2e10},
                                                              {"G", 3e9},
                                                              {"beta_A", 0.8},
                                                              {"c_F", 4.0},
                                                              {"p_ref", 2e9},
                                                              {"m_e", 2e-3},
                                                              {"M_ss", 0.45},
                                                              {"beta_s", 40.0}});
  testing::SyntheticSpec spec;
  spec.directions = 8;
  spec.plastic_amplitude = 2e-3;
  spec.path_end = -0.05;
  spec.path_samples = 8;
  spec.noise = {0.005, 4};
  const CalibrationData d = testing::synthetic_data(*law, spec);
  const fs::path file = dir / "results.h5";
  ResultsWriter w(file);
  w.attr("/material", "k_star", kKStar);
  double eps = -0.01;
  for (const auto& s : d.states) {
    const std::string g = "/states/" + s.label;
    w.write(g + "/stress", s.stress);
    w.write(g + "/fabric", s.fabric);
    w.attr(g, "volume_fraction", s.volume_fraction);
    w.attr(g, "eps_dev", eps);
    eps *= 2.0;
    for (const auto& e : s.envelopes) {
      const std::string eg = g + "/envelopes/" + e.name;
      w.attr(eg, "amplitude", e.amplitude);
      w.attr(eg, "method", "dynamic");
      w.write(eg + "/theta_deg", e.theta_deg);
      w.write(eg + "/strain", e.strain);
      std::vector<Eigen::Vector2d> star;
      for (const auto& p : e.stress) star.push_back(p / kKStar);
      w.write(eg + "/stress_star", star);
      w.write(eg + "/fabric", e.fabric);
    }
  }
  for (std::size_t k = 0; k < d.path.eps_dev.size(); ++k) {
    w.append("/path/eps_dev", d.path.eps_dev[k]);
    w.append("/path/stress", d.path.stress[k]);
    w.append("/path/stress_star", Eigen::Matrix3d(d.path.stress[k] / kKStar));
    w.append("/path/fabric", d.path.fabric[k]);
  }
  w.commit();
  return file;
}

int run(const std::string& args, const fs::path& log) {
  const int rc = std::system(
      (std::string(RENDULIC_EXE) + " " + args + " > " + log.string() + " 2>&1").c_str());
  return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

std::string slurp(const fs::path& p) {
  std::ifstream f(p);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

TEST(Overlay, FiguresAndReportShowEveryCalibratedLaw) {
  const fs::path dir = fs::path(RENDULIC_TEST_TMP) / "calibration_overlay";
  const fs::path file = make_file(dir);
  const fs::path log = dir / "log.txt";
  const std::vector<std::string> laws = {"isotropic_elastic", "hypoplastic_wu",
                                         "elastoplastic_fabric"};
  for (const auto& m : laws)
    ASSERT_EQ(run("calibrate --results " + file.string() + " --model " + m + " --out " +
                      (dir / (m + ".json")).string(),
                  log),
              0)
        << slurp(log);
  // The default held-out state (s1 of s0..s3) and the termination are in the JSON.
  const std::string j = slurp(dir / "elastoplastic_fabric.json");
  const nlohmann::json parsed = nlohmann::json::parse(j);
  EXPECT_EQ(parsed["held_out_states"], nlohmann::json::array({"s1"})) << j;
  EXPECT_TRUE(parsed.contains("termination"));
  {
    const ResultsReader r(file);
    EXPECT_EQ(r.attr_string("/calibration", "selected_model"), "elastoplastic_fabric")
        << r.attr_string("/calibration", "selection");
    EXPECT_TRUE(r.exists("/calibration/elastoplastic_fabric/path/stress"));
  }
  ASSERT_EQ(run("plot " + file.string() + " --out " + (dir / "figs").string(), log), 0)
      << slurp(log);
  for (const char* fig : {"models_elastic_stress", "models_plastic_stress", "models_elastic_fabric",
                          "models_plastic_fabric", "models_path"}) {
    const fs::path png = dir / "figs" / (std::string(fig) + ".png");
    const fs::path svg = dir / "figs" / (std::string(fig) + ".svg");
    ASSERT_TRUE(fs::exists(png)) << png;
    EXPECT_GT(fs::file_size(png), 1000u);
    const std::string text = slurp(svg);
    const bool fabric = std::string(fig).find("fabric") != std::string::npos;
    for (const auto& m : laws) {
      const std::string named = fabric && m == "hypoplastic_wu" ? "no fabric: " + m : m;
      EXPECT_NE(text.find(named), std::string::npos) << fig << " does not name " << named;
    }
  }
  ASSERT_EQ(run("report " + file.string() + " --no-figures", log), 0) << slurp(log);
  const std::string md = slurp(dir / "report.md");
  EXPECT_NE(md.find("## Model selection"), std::string::npos) << md;
  EXPECT_NE(md.find("This scene needs elastoplastic_fabric"), std::string::npos) << md;
  EXPECT_NE(md.find("| **elastoplastic_fabric** |"), std::string::npos) << md;
}

}  // namespace
}  // namespace rendulic::calibration

// Frictional states through a results file (docs/dem.md "Friction" and "States at rest"): a
// frictional packing sheared so that its contacts carry springs and some slide is brought to
// rest (the dynamic relaxation alone, its balance of forces and torques reported), written as
// a state with its checkpoint and read back; both then continue bit-identically (angular
// velocities, torques and tangential springs included), and so does a servo-held state. A
// frictional scenario that asks for a static tool is refused at once, naming the keys, before
// any simulation.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "cli_runner.hpp"
#include "packing_system.hpp"
#include "rendulic/core/result_paths.hpp"
#include "rendulic/core/results.hpp"
#include "rendulic/dem/protocols.hpp"
#include "rendulic/dem/rest.hpp"
#include "stages.hpp"
#include "tiny_run.hpp"

namespace rendulic::app {
namespace {
namespace fs = std::filesystem;
using rendulic::testing::CliResult;
using rendulic::testing::run_rendulic;

const fs::path kRoot = fs::path(RENDULIC_TEST_TMP) / "app_friction_state";

std::vector<double> flat(const dem::DemSystem& s) {
  const dem::Particles& p = s.particles();
  std::vector<double> v;
  for (const auto* a : {&p.x, &p.y, &p.z, &p.vx, &p.vy, &p.vz, &p.fx, &p.fy, &p.fz, &p.wx, &p.wy,
                        &p.wz, &p.tx, &p.ty, &p.tz})
    v.insert(v.end(), a->begin(), a->end());
  const dem::State st = s.save();
  v.insert(v.end(), st.tangential_history.begin(), st.tangential_history.end());
  v.push_back(st.sliding_dissipation);
  v.push_back(s.time());
  return v;
}

dem::SystemOptions frictional() {
  dem::SystemOptions o;
  o.material.mu = 0.5;
  return o;
}

// 400 particles compressed past jamming with a strong damping, then sheared at constant
// volume: lasting contacts with springs, some at the Coulomb limit.
dem::DemSystem sheared() {
  dem::SystemOptions o = frictional();
  o.material.gamma_b = 10.0;
  dem::GasOptions g;
  g.n_particles = 400;
  g.velocity = 0.0;
  dem::DemSystem s = dem::make_gas(o, g, 3);
  dem::CompressOptions c;
  c.target_nu = 0.66;
  c.rate_max = c.rate_min = 3000.0;
  dem::compress_isotropic(s, c);
  dem::DemSystem out = dem::DemSystem::restore(s.save(), frictional());
  out.advance(3000, Eigen::Vector3d(-200.0, 100.0, 100.0));
  return out;
}

TEST(FrictionState, RestsWithTorquesAndContinuesBitIdenticallyThroughAResultsFile) {
  dem::DemSystem sys = sheared();
  const dem::Measures sheared_m = sys.measure();
  ASSERT_GT(sheared_m.pressure, 0.0);
  ASSERT_GT(sheared_m.sliding_dissipation, 0.0);
  ASSERT_GT(sheared_m.tangential_energy, 0.0);
  ASSERT_GE(sheared_m.sliding_fraction, 0.0);
  ASSERT_LE(sheared_m.sliding_fraction, 1.0);

  dem::RestOptions ro;
  ro.relax.kinetic_to_elastic = 1e-5;
  ro.relax.time_cap = 2e-3;
  const dem::RestSummary rest = dem::bring_to_rest(sys, ro);
  EXPECT_EQ(rest.minimised.iterations, 0);  // no energy to minimise
  EXPECT_EQ(sys.kinetic_energy(), 0.0);
  EXPECT_EQ(sys.rotational_energy(), 0.0);
  // The balance counts the tangential forces and their torques: independent sums over the
  // contact list must reproduce it (the torques' moments are nonzero on a sheared packing).
  EXPECT_GT(rest.at_rest.contacts, 0);
  EXPECT_GT(rest.after_relax.max_net_torque, 0.0);
  EXPECT_LT(rest.at_rest.ratio, rest.after_relax.ratio * 10.0);
  EXPECT_LT(rest.at_rest.ratio, 1e-2);

  fs::create_directories(kRoot);
  const fs::path file = kRoot / "state.h5";
  {
    ResultsWriter out(file);
    write_material(out, sys.options(), static_cast<std::int64_t>(sys.particles().size()));
    write_state(out, paths::state("a"), sys, rest, 1e-9, true);
    out.commit();
  }
  ResultsReader in(file);
  const std::string g = paths::state("a");
  EXPECT_NEAR(in.attr_double(g, "force_balance"), rest.at_rest.ratio, 1e-15);
  EXPECT_NEAR(in.attr_double(g, "torque_balance"), rest.at_rest.torque_ratio, 1e-15);
  EXPECT_FALSE(in.has_attr(g, "minimise_iterations"));
  std::optional<dem::DemSystem> back = restore_checkpoint(in, g, frictional());
  ASSERT_TRUE(back.has_value());
  EXPECT_EQ(flat(*back), flat(sys));
  // Both continue: sheared further, the springs advance, slide and rebuild alike.
  sys.advance(2000, Eigen::Vector3d(-200.0, 100.0, 100.0));
  back->advance(2000, Eigen::Vector3d(-200.0, 100.0, 100.0));
  EXPECT_EQ(flat(*back), flat(sys));
  EXPECT_GT(sys.save().tangential_history.size(), 0u);
}

// A state whose last step summed its stress (a servo step: the packing held at a lateral
// stress) writes that stress into its checkpoint (last_stress_diag), so the servo read back
// from the file continues on the same bits.
TEST(FrictionState, AServoStateContinuesBitIdenticallyThroughAResultsFile) {
  dem::DemSystem sys = sheared();
  const dem::CellControl control =
      dem::CellControl::drained_triaxial(-200.0, sys.measure().pressure);
  for (int k = 0; k < 20; ++k) sys.step(control);
  ASSERT_TRUE(sys.save().last_stress_known);
  fs::create_directories(kRoot);
  const fs::path file = kRoot / "servo.h5";
  {
    ResultsWriter out(file);
    write_material(out, sys.options(), static_cast<std::int64_t>(sys.particles().size()));
    write_state(out, paths::state("a"), sys, dem::RestSummary{}, 1e-9, true);
    out.commit();
  }
  ResultsReader in(file);
  EXPECT_EQ(in.read_vector(paths::state("a") + "/checkpoint/last_stress_diag").size(), 3u);
  std::optional<dem::DemSystem> back = restore_checkpoint(in, paths::state("a"), frictional());
  ASSERT_TRUE(back.has_value());
  for (int k = 0; k < 200; ++k) {
    sys.step(control);
    back->step(control);
  }
  EXPECT_EQ(flat(*back), flat(sys));
  EXPECT_EQ(back->cell().lengths(), sys.cell().lengths());
}

TEST(FrictionState, AFrictionalScenarioAskingForAStaticToolIsRefusedAtOnce) {
  const fs::path s = rendulic::testing::tiny_scenario(kRoot);
  // Minimisation among the probe methods, elastic range by minimisation (its default): each
  // named, exit 2, no results file. The linear_response stage is not refused (it has its
  // frictional path, docs/probes.md) and not named.
  const CliResult r = run_rendulic(
      "run " + s.string() + " --quiet --out " + (kRoot / "refused").string() +
      " --set dem.friction=0.5 --set 'probes.methods=[\"dynamic\",\"minimisation\"]'"
      " --set 'run.stages=[\"prepare\",\"isotropic\",\"path\",\"states\",\"elastic_range\","
      "\"probes\",\"linear_response\"]'");
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("dem.friction = 0.5"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("probes.methods"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("linear_response"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("elastic_range.method"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("[prepare] started"), std::string::npos) << r.out;
  EXPECT_FALSE(fs::exists(kRoot / "refused" / "results.h5"));
  // One line.
  std::size_t lines = 0;
  for (const char ch : r.out) lines += ch == '\n';
  EXPECT_LE(lines, 1u) << r.out;
}

TEST(FrictionState, TheDynamicMethodsRunAndTheSeriesCarryTheSliding) {
  const fs::path s = rendulic::testing::tiny_scenario(kRoot);
  const fs::path dir = kRoot / "run";
  const CliResult r = run_rendulic(
      "run " + s.string() + " --quiet --threads 1 --out " + dir.string() +
      " --set dem.friction=0.5 --set elastic_range.method=dynamic"
      " --set 'elastic_range.amplitudes=[5e-5,5e-3]'"
      " --set 'run.stages=[\"prepare\",\"isotropic\",\"path\",\"states\",\"elastic_range\","
      "\"probes\",\"fits\"]'");
  ASSERT_EQ(r.code, 0) << r.out;
  ResultsReader in(dir / "results.h5");
  for (const char* g : {paths::kIsotropic, paths::kPath}) {
    const std::vector<double> f = in.read_vector(std::string(g) + datasets::kSlidingFraction);
    const std::vector<double> w = in.read_vector(std::string(g) + datasets::kSlidingDissipation);
    const std::vector<double> e = in.read_vector(std::string(g) + datasets::kRotationalEnergy);
    ASSERT_FALSE(f.empty());
    ASSERT_EQ(f.size(), w.size());
    ASSERT_EQ(f.size(), e.size());
    for (std::size_t k = 0; k < f.size(); ++k) {
      EXPECT_GE(f[k], 0.0);
      EXPECT_LE(f[k], 1.0);
      EXPECT_GE(e[k], 0.0);
      if (k > 0) {
        EXPECT_GE(w[k], w[k - 1]);  // dissipated work only grows
      }
    }
  }
  const std::string env = paths::envelope(paths::state("a"), paths::envelope_name("dynamic", 2e-3));
  EXPECT_TRUE(in.has_attr(env, "sliding_probes_fraction")) << env;
  EXPECT_TRUE(in.exists(paths::state("a") + paths::kCheckpoint + datasets::kTangentialSprings));
}

}  // namespace
}  // namespace rendulic::app

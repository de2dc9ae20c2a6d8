// The DEM stages through the real `rendulic run` (docs/results.md): a tiny fast
// scenario writes /material, /isotropic, /path and /states with the documented datasets, its
// states at rest (the net-force bound recomputed from the stored positions) with their
// elastic range; the stored checkpoint restores a state whose measures reproduce the
// stored stress bit for bit; every bad DEM scenario value exits 2 and writes nothing.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "cli_runner.hpp"
#include "rendulic/core/results.hpp"
#include "rendulic/dem/protocols.hpp"
#include "rendulic/dem/rest.hpp"

namespace rendulic::dem {
namespace {
namespace fs = std::filesystem;

using CmdResult = rendulic::testing::CliResult;
CmdResult rendulic(const std::string& args) { return rendulic::testing::run_rendulic(args); }
fs::path fresh_dir(const std::string& name) {
  return rendulic::testing::fresh_dir("dem_run/" + name);
}

// quick.toml's physics on 250 particles with fast rates: a structural test, not a physical one.
std::string tiny_overrides() {
  return " --quiet --threads 1 --set dem.n_particles=250 --set preparation.rate=10000"
         " --set relax.time_cap=1e-5 --set isotropic.rate_max=5000 --set isotropic.rate_min=5000"
         " --set isotropic.samples=50 --set path.rate=5000 --set path.samples=20"
         " --set states.time_cap=1e-5 --set calibration.model=anisotropic_elastic"
         " --set 'elastic_range.amplitudes=[5e-5,1e-3]' --set 'probes.amplitudes=[5e-5,2e-3]'";
}

TEST(RunStages, TinyScenarioWritesTheInterfacesSchema) {
  const fs::path out = fresh_dir("tiny");
  const std::string scenario = std::string(RENDULIC_SOURCE_DIR) + "/data/scenarios/quick.toml";
  const CmdResult r = rendulic("run " + scenario + " --out " + out.string() + tiny_overrides());
  ASSERT_EQ(r.code, 0) << r.out;
  ResultsReader f(out / "results.h5");
  for (const char* a : {"k", "gamma", "gamma_b", "density", "r_mean", "w", "k_star", "dt"})
    EXPECT_TRUE(f.has_attr("/material", a)) << a;
  EXPECT_EQ(f.attr_int("/material", "n_particles"), 250);
  EXPECT_NEAR(f.attr_double("/material", "k_star"), 1e8 / 2e-3, 1e-3);

  const auto nu = f.read_vector("/isotropic/volume_fraction");
  ASSERT_EQ(nu.size(), 50u);
  EXPECT_NEAR(nu.front(), 0.64, 1e-9);
  EXPECT_NEAR(nu.back(), 0.82, 1e-9);
  for (const char* d : {"pressure", "pressure_star", "coordination", "coordination_nonrattler",
                        "rattler_fraction", "time"})
    EXPECT_EQ(f.read_vector(std::string("/isotropic/") + d).size(), 50u) << d;
  EXPECT_EQ(f.read_tensors("/isotropic/stress").size(), 50u);
  EXPECT_EQ(f.read_tensors("/isotropic/fabric").size(), 50u);

  const auto eps_dev = f.read_vector("/path/eps_dev");
  ASSERT_EQ(eps_dev.size(), 20u);
  EXPECT_NEAR(eps_dev.back(), -0.32, 1e-9);
  for (double v : f.read_vector("/path/eps_v")) EXPECT_NEAR(v, 0.0, 1e-9);  // undrained
  for (const char* d : {"time", "volume_fraction", "coordination", "coordination_nonrattler",
                        "kinetic_energy", "elastic_energy", "inertial_number"})
    EXPECT_EQ(f.read_vector(std::string("/path/") + d).size(), 20u) << d;
  for (const char* d : {"strain", "stress", "stress_star", "fabric"})
    EXPECT_EQ(f.read_tensors(std::string("/path/") + d).size(), 20u) << d;

  const std::vector<std::string> labels = {"a", "b", "c", "d", "e"};
  const std::vector<double> targets = {0.006, 0.021, 0.043, 0.068, 0.32};
  for (std::size_t k = 0; k < labels.size(); ++k) {
    const std::string g = "/states/" + labels[k];
    EXPECT_NEAR(f.attr_double(g, "eps_dev"), -targets[k], 1e-9) << g;
    for (const char* a : {"volume_fraction", "pressure_star", "coordination", "kinetic_to_elastic"})
      EXPECT_TRUE(f.has_attr(g, a)) << g << " " << a;
    EXPECT_EQ(f.shape(g + "/positions"), (std::vector<std::uint64_t>{250, 3}));
    EXPECT_EQ(f.read_vector(g + "/radii").size(), 250u);
    EXPECT_EQ(f.read_vector(g + "/cell_lengths").size(), 3u);
    // At rest (rest.hpp): the net force bound, recomputed from the stored configuration.
    const auto radii = f.read_vector(g + "/radii");
    const auto lengths = f.read_vector(g + "/cell_lengths");
    const PackingData stored = PackingData::orthorhombic(
        f.read_matrix(g + "/positions"), Eigen::Map<const Eigen::VectorXd>(radii.data(), 250),
        Eigen::Vector3d(lengths[0], lengths[1], lengths[2]));
    const ForceBalance b = force_balance(stored, 1e8);
    EXPECT_LT(b.ratio, kEquilibrium) << g;
    EXPECT_NEAR(b.ratio, f.attr_double(g, "force_balance"), 1e-6 * kEquilibrium) << g;
    EXPECT_GT(f.attr_double(g, "force_balance_relaxed"), b.ratio) << g;
    // The elastic range of the state, with its documented datasets.
    for (const char* d :
         {"amplitude", "minor_over_elastic", "center_over_a", "k_continue", "k_reverse"})
      EXPECT_EQ(f.read_vector(g + "/elastic_range/" + d).size(), 2u) << g << " " << d;
    EXPECT_TRUE(f.has_attr(g + "/elastic_range", "yield_strain")) << g;
    // The stored stress is the stress of the stored positions (the linear response's too).
    EXPECT_LE((measure_stress_fabric(stored, 1e8).stress - f.read_tensor(g + "/stress")).norm(),
              1e-9 * f.read_tensor(g + "/stress").norm())
        << g;
  }

  // Restart from the stored checkpoint of state c: the same build measures the same stress.
  const std::string g = "/states/c";
  State st;
  const Eigen::MatrixXd pos = f.read_matrix(g + "/positions");
  const Eigen::MatrixXd vel = f.read_matrix(g + "/checkpoint/velocities");
  const Eigen::MatrixXd frc = f.read_matrix(g + "/checkpoint/forces");
  const Eigen::MatrixXd ref = f.read_matrix(g + "/checkpoint/reference_positions");
  const auto radii = f.read_vector(g + "/radii");
  SystemOptions o;
  st.particles.resize(radii.size());
  for (std::size_t i = 0; i < radii.size(); ++i) {
    const auto r = static_cast<Eigen::Index>(i);
    st.particles.x[i] = pos(r, 0), st.particles.y[i] = pos(r, 1), st.particles.z[i] = pos(r, 2);
    st.particles.vx[i] = vel(r, 0), st.particles.vy[i] = vel(r, 1), st.particles.vz[i] = vel(r, 2);
    st.particles.fx[i] = frc(r, 0), st.particles.fy[i] = frc(r, 1), st.particles.fz[i] = frc(r, 2);
    st.particles.radius[i] = radii[i];
    st.particles.inv_mass[i] = 1.0 / o.material.sphere_mass(radii[i]);
  }
  st.ref_x.resize(radii.size()), st.ref_y.resize(radii.size()), st.ref_z.resize(radii.size());
  for (std::size_t i = 0; i < radii.size(); ++i) {
    const auto r = static_cast<Eigen::Index>(i);
    st.ref_x[i] = ref(r, 0), st.ref_y[i] = ref(r, 1), st.ref_z[i] = ref(r, 2);
  }
  auto vec3 = [&](const std::string& p) {
    const auto v = f.read_vector(p);
    return Eigen::Vector3d(v[0], v[1], v[2]);
  };
  st.lengths = vec3(g + "/cell_lengths");
  st.ref_lengths = vec3(g + "/checkpoint/reference_cell_lengths");
  st.ref_half_skin = f.read_vector(g + "/checkpoint/reference_half_skins");
  st.strain_E = vec3(g + "/checkpoint/strain_E");
  st.last_D = vec3(g + "/checkpoint/last_D");
  st.time = f.attr_double(g + "/checkpoint", "time");
  st.steps = f.attr_int(g + "/checkpoint", "steps");
  o.skin = 0.3;  // quick.toml's skin: the list must be the run's
  const DemSystem s = DemSystem::restore(st, o);
  EXPECT_EQ(s.measure().stress, f.read_tensor(g + "/stress"));  // exact
  EXPECT_EQ(s.measure().fabric, f.read_tensor(g + "/fabric"));
}

// The pressure branches (docs/dem.md): the loading copied at nu = 0.72 on its way to 0.82,
// and from there a path at the main path's inertial number, states at rest and their elastic
// range under /pressure/nu0.72.
TEST(RunStages, PressureBranchRepeatsThePathAndStatesAtALowerVolumeFraction) {
  const fs::path out = fresh_dir("pressure");
  const std::string scenario = std::string(RENDULIC_SOURCE_DIR) + "/data/scenarios/quick.toml";
  const CmdResult r = rendulic(
      "run " + scenario + " --out " + out.string() + tiny_overrides() +
      " --set 'run.stages=[\"prepare\",\"isotropic\",\"path\",\"states\",\"elastic_range\","
      "\"pressure\"]' --set 'pressure.volume_fractions=[0.72]' --set 'states.eps_dev=[0.006,0.32]'"
      " --set 'states.labels=[\"a\",\"e\"]'");
  ASSERT_EQ(r.code, 0) << r.out;
  ResultsReader f(out / "results.h5");
  const std::string g = "/pressure/nu0.72";
  EXPECT_NEAR(f.attr_double(g, "volume_fraction"), 0.72, 1e-9);
  EXPECT_LT(f.attr_double(g, "pressure_star"), f.attr_double("/states/a", "pressure_star"));
  const auto eps_dev = f.read_vector(g + "/path/eps_dev");
  ASSERT_EQ(eps_dev.size(), 20u);
  EXPECT_NEAR(eps_dev.back(), -0.32, 1e-9);
  // The same inertial number as the main path at the start of the steady state.
  const auto i_main = f.read_vector("/path/inertial_number");
  const auto i_branch = f.read_vector(g + "/path/inertial_number");
  EXPECT_NEAR(i_branch[1], i_main[1], 0.3 * i_main[1]);
  EXPECT_LT(f.attr_double(g + "/path", "rate"), f.attr_double("/path", "rate"));
  for (const char* label : {"a", "e"}) {
    const std::string sg = g + "/states/" + label;
    EXPECT_LT(f.attr_double(sg, "force_balance"), kEquilibrium) << sg;
    EXPECT_NEAR(f.attr_double(sg, "volume_fraction"), 0.72, 1e-9) << sg;
    EXPECT_TRUE(f.has_attr(sg + "/elastic_range", "yield_strain")) << sg;
    EXPECT_FALSE(f.exists(sg + "/positions")) << sg;
  }
}

TEST(RunStages, BadDemValuesExitTwoAndWriteNothing) {
  const std::string scenario = std::string(RENDULIC_SOURCE_DIR) + "/data/scenarios/quick.toml";
  const std::vector<std::string> bad = {
      "dem.dt_factor=0.5",                      // beyond the stability limit
      "material.k=-1",                          // out of range
      "isotropic.nu_max=0.6",                   // below nu0
      "states.labels=[\"a\",\"b\"]",            // one label per state
      "states.eps_dev=[0.006,0.5]",             // beyond path.eps_dev_max (and labels mismatch)
      "dem.n_particles=10",                     // too few
      "preparation.nu_gas=0.5",                 // random insertion cannot reach it
      "path.rate=0",                            // not a rate
      "probes.dt_factor=0.5",                   // the probes' step beyond the stability limit
      "pressure.volume_fractions=[0.9]",        // beyond isotropic.nu_max
      "run.stages=[\"prepare\",\"pressure\"]",  // a pressure stage without volume fractions
      "elastic_range.amplitudes=[1e-3,1e-4]",   // a ladder must increase
  };
  for (std::size_t k = 0; k < bad.size(); ++k) {
    const fs::path out = fresh_dir("bad" + std::to_string(k));
    const CmdResult r =
        rendulic("run " + scenario + " --out " + out.string() + " --quiet --set '" + bad[k] + "'");
    EXPECT_EQ(r.code, 2) << bad[k] << ": " << r.out;
    EXPECT_FALSE(fs::exists(out / "results.h5")) << bad[k];
    std::size_t files = 0;
    for (const auto& e : fs::directory_iterator(out)) files += e.is_regular_file();
    EXPECT_EQ(files, 0u) << bad[k];
  }
}

}  // namespace
}  // namespace rendulic::dem

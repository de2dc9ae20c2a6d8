// `rendulic export --lammps` (docs/interop.md): the data file holds the stored state exactly
// (positions, radii, velocities read back to the same doubles), and LAMMPS, an independent
// implementation of the same contact law, computes from it the stress the results file stored,
// to round-off, with the pair settings docs/interop.md gives (skipped where Debian's `lmp` is
// not installed).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include "cli_runner.hpp"
#include "rendulic/core/packing_file.hpp"
#include "rendulic/core/result_paths.hpp"
#include "rendulic/core/results.hpp"
#include "tiny_run.hpp"

namespace {
namespace fs = std::filesystem;
using rendulic::testing::have_lammps;
using rendulic::testing::run_command;
using rendulic::testing::run_rendulic;

// The LAMMPS input of docs/interop.md "Checking a state in LAMMPS": read the data file, the pair
// settings `rendulic export` printed, the virial stress after `run 0`, printed in full.
std::string lammps_input(const std::string& pair_lines) {
  return "units si\natom_style sphere\nboundary p p p\ncomm_modify vel yes\n"
         "read_data ${data}\n" +
         pair_lines +
         "compute sigma all pressure NULL virial\n"
         "thermo_style custom step c_sigma[1]\n"
         "run 0\n"
         "print \"STRESS $(c_sigma[1]:%.17g) $(c_sigma[2]:%.17g) $(c_sigma[3]:%.17g) "
         "$(c_sigma[4]:%.17g) $(c_sigma[5]:%.17g) $(c_sigma[6]:%.17g)\"\n";
}

TEST(Export, DataFileHoldsTheStoredStateExactlyAndLammpsReproducesItsStress) {
  const fs::path results = rendulic::testing::tiny_results();
  const fs::path dir = rendulic::testing::fresh_dir("app_export/state_a");
  const fs::path data = dir / "a.data";
  const auto r =
      run_rendulic("export " + results.string() + " --state a --lammps " + data.string(), false);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("pair_coeff * * hooke 100000000 1 damping velocity"), std::string::npos)
      << r.out;

  // Read back: the same doubles, in the same order.
  const rendulic::ResultsReader in(results);
  const std::string g = rendulic::paths::state("a");
  const Eigen::MatrixXd x = in.read_matrix(g + rendulic::datasets::kPositions);
  const std::vector<double> radii = in.read_vector(g + rendulic::datasets::kRadii);
  const Eigen::MatrixXd v =
      in.read_matrix(g + rendulic::paths::kCheckpoint + rendulic::datasets::kVelocities);
  const rendulic::Packing p = rendulic::read_lammps_data(data);
  ASSERT_EQ(p.size(), radii.size());
  EXPECT_EQ(p.radii, radii);
  EXPECT_TRUE(p.positions == x);
  EXPECT_TRUE(p.velocities == v);
  const std::vector<double> L = in.read_vector(g + rendulic::datasets::kCellLengths);
  EXPECT_EQ(p.lengths, Eigen::Vector3d(L[0], L[1], L[2]));
  for (double d : p.densities) EXPECT_EQ(d, in.attr_double("/material", "density"));

  if (!have_lammps()) GTEST_SKIP() << "lmp not installed: the LAMMPS check is skipped";
  std::ofstream(dir / "in.stress") << lammps_input(r.out);
  const auto l =
      run_command("cd " + dir.string() + " && lmp -nocite -log none -echo none -var data " +
                  data.string() + " -in in.stress");
  ASSERT_EQ(l.code, 0) << l.out;
  const std::regex line("STRESS ([^ ]+) ([^ ]+) ([^ ]+) ([^ ]+) ([^ ]+) ([^ \n]+)");
  std::smatch m;
  ASSERT_TRUE(std::regex_search(l.out, m, line)) << l.out;
  // LAMMPS's order: xx, yy, zz, xy, xz, yz.
  const int ij[6][2] = {{0, 0}, {1, 1}, {2, 2}, {0, 1}, {0, 2}, {1, 2}};
  const Eigen::Matrix3d stored = in.read_tensor(g + rendulic::datasets::kStress);
  const double p_stored = stored.trace() / 3;
  ASSERT_GT(p_stored, 0);
  for (int k = 0; k < 6; ++k) {
    const double lammps = std::stod(m[k + 1].str());
    // Round-off: the sums run over ~750 contacts in another order.
    EXPECT_NEAR(lammps, stored(ij[k][0], ij[k][1]), 1e-12 * p_stored)
        << "component " << k << " (LAMMPS " << lammps << ")";
  }
}

TEST(Export, RefusesAStateThatIsNotThere) {
  const fs::path results = rendulic::testing::tiny_results();
  const fs::path dir = rendulic::testing::fresh_dir("app_export/missing");
  const auto r = run_rendulic(
      "export " + results.string() + " --state zz --lammps " + (dir / "z.data").string(), false);
  EXPECT_EQ(r.code, 2);
  EXPECT_EQ(rendulic::testing::error_lines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("/states/zz"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "z.data"));
}

// A stored material that is not one (NaN, negative): export wrote `pair_coeff * * hooke nan`
// and atoms of density -5 with exit 0.
TEST(Export, AMaterialValueThatIsNotOneIsRefusedNamingIt) {
  const fs::path dir = rendulic::testing::fresh_dir("app_export/material");
  for (const auto& [key, value] :
       {std::pair<const char*, double>{"k", std::nan("")}, {"density", -5.0}, {"dt", INFINITY}}) {
    const fs::path results = dir / (std::string(key) + ".h5");
    fs::copy_file(rendulic::testing::tiny_results(), results, fs::copy_options::overwrite_existing);
    {
      rendulic::ResultsWriter w = rendulic::ResultsWriter::update(results);
      w.attr(rendulic::paths::kMaterial, key, value);
      w.commit();
    }
    const auto r = run_rendulic(
        "export " + results.string() + " --state a --lammps " + (dir / "x.data").string(), false);
    EXPECT_EQ(r.code, 2) << key;
    EXPECT_EQ(rendulic::testing::error_lines(r.err), 1) << r.err;
    EXPECT_NE(r.err.find(results.string() + ":/material@" + key + " is "), std::string::npos)
        << r.err;
    EXPECT_FALSE(fs::exists(dir / "x.data"));
  }
}

// A disk that refuses bytes (here a file-size limit of 4 KiB, SIGXFSZ ignored as a full disk
// sends none): one line naming the file, and an earlier export of the same name left whole.
// Before AtomicTextFile the data file was written in place and 4 KiB of it stayed.
TEST(Export, ADiskThatRefusesBytesLeavesTheEarlierDataFileWhole) {
  const fs::path results = rendulic::testing::tiny_results();
  const fs::path dir = rendulic::testing::fresh_dir("app_export/limit");
  const fs::path data = dir / "a.data";
  std::ofstream(data) << "an earlier export\n";
  const auto r =
      run_command("trap '' XFSZ; ulimit -f 4; exec " + std::string(RENDULIC_EXE) + " export " +
                      results.string() + " --state a --lammps " + data.string(),
                  false);
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_EQ(rendulic::testing::error_lines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("a.data: cannot write the LAMMPS data file: File too large"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(rendulic::testing::read_file(data), "an earlier export\n");
  for (const auto& e : fs::directory_iterator(dir)) EXPECT_EQ(e.path(), data);
}

// A frictional run with rolling resistance: export prints the stored material's tangential
// and rolling settings (docs/interop.md "Friction against LAMMPS"), and LAMMPS accepts them.
TEST(Export, PrintsTheFrictionAndRollingSettingsOfTheStoredMaterial) {
  const fs::path dir = rendulic::testing::fresh_dir("app_export/rolling");
  const auto run = run_rendulic(
      "run " + (fs::path(RENDULIC_SOURCE_DIR) / "data/scenarios/quick.toml").string() +
          " --quiet --out " + (dir / "run").string() +
          " --set 'run.stages=[\"prepare\",\"isotropic\",\"path\",\"states\"]' "
          "--set dem.n_particles=100 --set dem.friction=0.5 --set dem.rolling_friction=0.1 "
          "--set dem.k_r_ratio=0.25 --set dem.gamma_r_ratio=0.5 --set isotropic.nu_max=0.66 "
          "--set path.eps_dev_max=0.002 --set 'states.eps_dev=[0.001]' "
          "--set 'states.labels=[\"a\"]'",
      false);
  ASSERT_EQ(run.code, 0) << run.err;
  const fs::path data = dir / "a.data";
  const auto r = run_rendulic(
      "export " + (dir / "run" / "results.h5").string() + " --state a --lammps " + data.string(),
      false);
  ASSERT_EQ(r.code, 0) << r.err;
  // k_t = 2/7 k, x_gamma_t = 2/7 (the defaults); k_r = 0.25 k, gamma_r = 0.5 gamma (1 kg/s).
  EXPECT_NE(r.out.find("tangential linear_history 28571428.571428571 0.2857142857142857 0.5 "
                       "rolling sds 25000000 0.5 0.10000000000000001\n"),
            std::string::npos)
      << r.out;
  if (!have_lammps()) GTEST_SKIP() << "lmp not installed: the LAMMPS check is skipped";
  std::ofstream(dir / "in.stress") << lammps_input(r.out);
  const auto l =
      run_command("cd " + dir.string() + " && lmp -nocite -log none -echo none -var data " +
                  data.string() + " -in in.stress");
  EXPECT_EQ(l.code, 0) << l.out;
  EXPECT_NE(l.out.find("STRESS "), std::string::npos) << l.out;
}

// `rendulic bench --lammps DIR --friction MU` (docs/performance.md "Against LAMMPS"): each
// timed state as a data file and each timed contact law as pair lines, those `rendulic export`
// prints for the same material, and LAMMPS reads every state with both laws.
TEST(BenchLammps, WritesTheStatesAndTheTimedContactLawsForLammps) {
  const fs::path dir = rendulic::testing::fresh_dir("app_export/bench");
  const auto r = run_rendulic(
      "bench --particles 200 --threads 1 --repetitions 1 --seconds 0.01 "
      "--friction 0.5 --lammps " +
          dir.string(),
      false);
  ASSERT_EQ(r.code, 0) << r.err;
  auto text = [](const fs::path& f) {
    std::ostringstream s;
    s << std::ifstream(f).rdbuf();
    return s.str();
  };
  for (const char* nu : {"nu64", "nu82"}) {
    const fs::path data = dir / (std::string(nu) + ".data");
    ASSERT_TRUE(fs::exists(data)) << data;
    const std::string smooth = text(dir / (std::string(nu) + ".pair"));
    const std::string rough = text(dir / (std::string(nu) + "-friction.pair"));
    EXPECT_EQ(smooth,
              "pair_style granular\npair_coeff * * hooke 100000000 1 damping velocity "
              "tangential linear_nohistory 0 0\n");
    // k_t = 2/7 k and x_gamma_t = 2/7 (the defaults), mu as asked.
    EXPECT_EQ(rough,
              "pair_style granular\npair_coeff * * hooke 100000000 1 damping velocity "
              "tangential linear_history 28571428.571428571 0.2857142857142857 0.5\n");
    if (!have_lammps()) continue;
    for (const std::string& pair : {smooth, rough}) {
      std::ofstream(dir / "in.stress") << lammps_input(pair);
      const auto l =
          run_command("cd " + dir.string() + " && lmp -nocite -log none -echo none -var data " +
                      data.string() + " -in in.stress");
      EXPECT_EQ(l.code, 0) << l.out;
      EXPECT_NE(l.out.find("STRESS "), std::string::npos) << l.out;
    }
  }
  if (!have_lammps()) GTEST_SKIP() << "lmp not installed: the LAMMPS check is skipped";
}

}  // namespace

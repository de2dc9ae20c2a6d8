// Probe campaigns across MPI ranks through the real binary (probe_mpi.hpp):
// `mpirun -np 2 rendulic run` writes envelopes bitwise equal to a plain single-process run of
// the same scenario (each probe is a function of state, direction and options only, and the
// workers get the state bit for bit), only rank 0 prints and writes, and an error on rank 0
// exits promptly with its one line and releases the worker. The plain run is also the check
// that an MPI build launched without mpirun works as a single process.
// Needs a build with -DRENDULIC_MPI=ON (CI builds so); otherwise the tests skip and say why.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "cli_runner.hpp"
#include "rendulic/core/results.hpp"
#include "rendulic/dem/probe_mpi.hpp"

namespace rendulic::dem {
namespace {
namespace fs = std::filesystem;
using rendulic::testing::CliResult;

// `timeout` turns a hang into a failure (exit 124) instead of a stuck suite; the bound is
// far above the seconds these runs take. CI runs as root in a container: hence
// --allow-run-as-root, and no single-copy (ptrace-based) shared-memory transfers, which
// containers without CAP_SYS_PTRACE refuse.
std::string mpirun(int ranks) {
  return "OMPI_MCA_btl_vader_single_copy_mechanism=none timeout 300 mpirun --allow-run-as-root "
         "--oversubscribe -np " +
         std::to_string(ranks) + " " + RENDULIC_EXE;
}

// quick.toml's physics on 250 particles, one state, eight directions, both probe methods and
// the linear response: a structural test of the distribution, seconds on 2 cores.
std::string tiny_scenario(const fs::path& out) {
  return " run " + std::string(RENDULIC_SOURCE_DIR) + "/data/scenarios/quick.toml --out " +
         out.string() +
         " --threads 1 --set dem.n_particles=250 --set preparation.rate=10000"
         " --set relax.time_cap=1e-5 --set isotropic.rate_max=5000 --set isotropic.rate_min=5000"
         " --set isotropic.samples=50 --set path.rate=5000 --set path.samples=20"
         " --set states.time_cap=1e-5 --set 'states.eps_dev=[0.068]' --set states.labels=d"
         " --set run.stages=prepare,isotropic,path,states,probes,linear_response"
         " --set probes.directions=8 --set probes.methods=dynamic,minimisation"
         " --set probes.relax_time_cap=2e-4 --set probes.force_tolerance=1e-7";
}

std::size_t count(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (auto at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

TEST(ProbeMpi, TwoRanksWriteBitwiseTheEnvelopesOfOneProcess) {
  if (!built_with_mpi()) GTEST_SKIP() << "built without MPI (cmake -DRENDULIC_MPI=ON to test)";
  const fs::path one = rendulic::testing::fresh_dir("probe_mpi/one");
  const fs::path two = rendulic::testing::fresh_dir("probe_mpi/two");
  const CliResult single = rendulic::testing::run_rendulic(tiny_scenario(one));
  ASSERT_EQ(single.code, 0) << single.out;
  const CliResult ranks = rendulic::testing::run_command(mpirun(2) + tiny_scenario(two));
  ASSERT_EQ(ranks.code, 0) << ranks.out;
  EXPECT_EQ(count(ranks.out, "2 MPI ranks share the probe campaigns"), 1u) << ranks.out;
  // Progress comes from rank 0 alone: each stage starts once, as in the single run.
  EXPECT_EQ(count(ranks.out, "rendulic: [probes] started"), 1u) << ranks.out;
  EXPECT_EQ(count(ranks.out, "rendulic: wrote"), 1u) << ranks.out;
  // Nothing but rank 0's results file in the folder.
  std::vector<std::string> files;
  for (const auto& e : fs::directory_iterator(two)) files.push_back(e.path().filename());
  EXPECT_EQ(files, std::vector<std::string>{"results.h5"});

  const ResultsReader a(one / "results.h5"), b(two / "results.h5");
  int envelopes = 0;
  for (const std::string& state : a.children("/states")) {
    const std::string g = "/states/" + state + "/envelopes";
    ASSERT_EQ(a.children(g), b.children(g)) << g;
    for (const std::string& name : a.children(g)) {
      const std::string e = g + "/" + name;
      ++envelopes;
      // Bitwise: exact equality of every double, no tolerance.
      EXPECT_EQ(a.read_tensors(e + "/d_stress"), b.read_tensors(e + "/d_stress")) << e;
      EXPECT_EQ(a.read_tensors(e + "/d_fabric"), b.read_tensors(e + "/d_fabric")) << e;
      EXPECT_EQ(a.read_pairs(e + "/stress_star"), b.read_pairs(e + "/stress_star")) << e;
      const std::vector<std::string> diagnostics = a.attr_strings(e, "diagnostics");
      if (a.attr_string(e, "method") != "linear_response") {
        EXPECT_FALSE(diagnostics.empty()) << e;
      }
      for (const std::string& d : diagnostics)
        EXPECT_EQ(a.read_vector(e + "/" + d), b.read_vector(e + "/" + d)) << e << "/" << d;
      for (const std::string& t : a.attr_strings(e, "attributes")) {
        if (t == "seconds") continue;  // the linear response's wall time, not a result
        EXPECT_EQ(a.attr_double(e, t), b.attr_double(e, t)) << e << " " << t;
      }
    }
  }
  // (dynamic, minimisation, linear_response) x 2 amplitudes.
  EXPECT_EQ(envelopes, 6);
}

TEST(ProbeMpi, AnErrorOnRankZeroExitsPromptlyWithOneLine) {
  if (!built_with_mpi()) GTEST_SKIP() << "built without MPI (cmake -DRENDULIC_MPI=ON to test)";
  const fs::path out = rendulic::testing::fresh_dir("probe_mpi/bad");
  const CliResult r = rendulic::testing::run_command(
      mpirun(2) + " run " + std::string(RENDULIC_SOURCE_DIR) + "/data/scenarios/quick.toml --out " +
      out.string() + " --set probes.no_such_key=1");
  EXPECT_NE(r.code, 0) << r.out;
  EXPECT_NE(r.code, 124) << "timed out: a rank hung\n" << r.out;
  EXPECT_EQ(count(r.out, "rendulic: --set probes.no_such_key=1: unknown key"), 1u) << r.out;
  EXPECT_EQ(count(r.out, "MPI_ABORT"), 0u) << r.out;
  EXPECT_FALSE(fs::exists(out / "results.h5"));
}

}  // namespace
}  // namespace rendulic::dem

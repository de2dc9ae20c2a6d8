// `rendulic probe` (docs/interop.md) against independent routes to the same numbers:
//  - a results file's state probed again gives the envelopes and fits the run stored (the state
//    restarts from its checkpoint, with the run's own scenario);
//  - a state exported to a LAMMPS data file and imported again is the same packing, at rest as
//    read (nothing moved), and the data file, a LAMMPS dump of it (written by LAMMPS when `lmp`
//    is installed, with its units and time items, and by this test in another column layout)
//    and the results file's state give the same linear-response envelopes;
//  - a packing away from equilibrium is brought to rest, and the report says what moved;
//  - a packing at a saddle of its energy has no linear response, until --leave-saddle moves it
//    off to a minimum;
//  - bad packing files exit 2 with one line and write nothing, and so does a results file's
//    state probed with another dem.skin than its list was made with or with a number in its
//    checkpoint that is not finite;
//  - probe planes: a deviatoric envelope beside the unchanged Rendulic one, an unknown plane
//    refused.
#include <H5Cpp.h>
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <algorithm>
#include <cerrno>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <limits>
#include <numeric>
#include <sstream>

#include "cli_runner.hpp"
#include "rendulic/core/packing_file.hpp"
#include "rendulic/core/result_paths.hpp"
#include "rendulic/core/results.hpp"
#include "rendulic/dem/probe_minimise.hpp"
#include "tiny_run.hpp"

namespace {
namespace fs = std::filesystem;
using rendulic::ResultsReader;
using rendulic::testing::CliResult;
using rendulic::testing::run_command;
using rendulic::testing::run_rendulic;
namespace ds = rendulic::datasets;
namespace paths = rendulic::paths;

const fs::path kRoot = fs::path(RENDULIC_TEST_TMP) / "app_probe";

fs::path tiny() { return rendulic::testing::tiny_results(); }

CliResult probe(const std::string& args) {
  return run_rendulic("probe " + args + " --quiet --threads 1", false);
}

// The largest difference of two stacks of tensors over the largest entry of the first.
double relative_difference(const std::vector<Eigen::Matrix3d>& a,
                           const std::vector<Eigen::Matrix3d>& b) {
  EXPECT_EQ(a.size(), b.size());
  double diff = 0, scale = 0;
  for (std::size_t k = 0; k < std::min(a.size(), b.size()); ++k) {
    diff = std::max(diff, (a[k] - b[k]).cwiseAbs().maxCoeff());
    scale = std::max(scale, a[k].cwiseAbs().maxCoeff());
  }
  return scale > 0 ? diff / scale : diff;
}

void expect_same_envelope(const ResultsReader& a, const std::string& ga, const ResultsReader& b,
                          const std::string& gb, double tolerance) {
  SCOPED_TRACE(ga + " vs " + gb);
  EXPECT_LE(
      relative_difference(a.read_tensors(ga + ds::kDStress), b.read_tensors(gb + ds::kDStress)),
      tolerance);
  EXPECT_LE(
      relative_difference(a.read_tensors(ga + ds::kDFabric), b.read_tensors(gb + ds::kDFabric)),
      tolerance);
  EXPECT_EQ(a.read_vector(ga + ds::kThetaDeg), b.read_vector(gb + ds::kThetaDeg));
}

TEST(Probe, AResultsFileStateGivesTheStoredEnvelopesAndFits) {
  const fs::path base = tiny();
  const fs::path out = rendulic::testing::fresh_dir("app_probe/state_b");
  const CliResult r =
      probe(base.string() + ":/states/b --label b --methods dynamic --out " + out.string());
  ASSERT_EQ(r.code, 0) << r.err;
  const ResultsReader stored(base), again(out / "results.h5");
  const std::string g = paths::state("b");
  for (const std::string& name : stored.children(paths::envelopes(g))) {
    const std::string e = paths::envelope(g, name);
    // The same state, restarted bit for bit, under the same scenario: the same numbers.
    expect_same_envelope(stored, e, again, e, 0.0);
    EXPECT_EQ(stored.attr_doubles(e + paths::kFitStress, "semi_axes"),
              again.attr_doubles(e + paths::kFitStress, "semi_axes"));
  }
  EXPECT_EQ(stored.read_tensor(g + ds::kStress), again.read_tensor(g + ds::kStress));
  EXPECT_EQ(again.attr_int(g, "minimise_iterations"), 0);  // at rest as stored: nothing moved
}

// A minimisation probe too small for its force tolerance keeps part of the affine response
// (dem::kMinAffineForceOverTolerance): the run says so per envelope, and not for one well above.
TEST(Probe, AMinimisationEnvelopeTooSmallForTheForceToleranceIsWarnedAbout) {
  const fs::path base = tiny();
  const fs::path out = rendulic::testing::fresh_dir("app_probe/too_small");
  const CliResult r = probe(base.string() +
                            ":/states/b --label b --methods minimisation --directions 8 "
                            "--amplitudes 1e-12,5e-5 --out " +
                            out.string());
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("warning: /states/b/envelopes/minimisation_1e-12: the affine step leaves "
                       "net forces of only "),
            std::string::npos)
      << r.err;
  EXPECT_EQ(r.err.find("minimisation_5e-05: the affine step"), std::string::npos) << r.err;
  const ResultsReader again(out / "results.h5");
  EXPECT_LT(
      again.attr_double("/states/b/envelopes/minimisation_1e-12", "affine_force_over_tolerance"),
      100.0);
}

// A results file whose stored scenario does not parse (written by another version): the probes
// take the material from /material, here with k doubled, which doubles every stress increment
// of the linear response (the positions at rest do not depend on k) and says so in a warning.
TEST(Probe, AStoredScenarioThatDoesNotParseLeavesTheStoredMaterial) {
  const fs::path base = tiny();
  const fs::path dir = rendulic::testing::fresh_dir("app_probe/old_scenario");
  const fs::path copy = dir / "old.h5";
  fs::copy_file(base, copy);
  {
    H5::H5File h(copy.string(), H5F_ACC_RDWR);
    h.removeAttr("scenario");
    const std::string text = "[dem]\nkey_of_another_version = 1\n";
    const H5::StrType type(H5::PredType::C_S1, H5T_VARIABLE);
    h.createAttribute("scenario", type, H5::DataSpace(H5S_SCALAR)).write(type, text);
    const double k = 2 * ResultsReader(base).attr_double(paths::kMaterial, "k");
    h.openGroup(paths::kMaterial).openAttribute("k").write(H5::PredType::NATIVE_DOUBLE, &k);
  }
  const std::string args = ":a --methods linear_response --directions 6 --out ";
  const CliResult ref = probe(base.string() + args + (dir / "ref").string());
  ASSERT_EQ(ref.code, 0) << ref.err;
  const CliResult old = probe(copy.string() + args + (dir / "old").string());
  ASSERT_EQ(old.code, 0) << old.err;
  EXPECT_NE(old.err.find("warning: the scenario stored in " + copy.string() +
                         " does not parse with this version"),
            std::string::npos)
      << old.err;
  const ResultsReader a(dir / "ref" / "results.h5"), b(dir / "old" / "results.h5");
  const std::string g = paths::state("a");
  EXPECT_EQ(b.attr_double(paths::kMaterial, "k"), 2 * a.attr_double(paths::kMaterial, "k"));
  for (const std::string& name : a.children(paths::envelopes(g))) {
    std::vector<Eigen::Matrix3d> doubled = a.read_tensors(paths::envelope(g, name) + ds::kDStress);
    for (auto& t : doubled) t *= 2;
    EXPECT_LE(relative_difference(doubled, b.read_tensors(paths::envelope(g, name) + ds::kDStress)),
              1e-9)
        << name;
  }
}

// The state as a LAMMPS dump in another layout than LAMMPS writes: atoms in reverse order,
// radius instead of diameter, scaled coordinates, an extra column.
void write_dump(const rendulic::Packing& p, const fs::path& file) {
  std::ofstream out(file);
  out << std::setprecision(17) << "ITEM: TIMESTEP\n0\nITEM: NUMBER OF ATOMS\n"
      << p.size() << "\nITEM: BOX BOUNDS pp pp pp\n";
  for (int a = 0; a < 3; ++a) out << "0 " << p.lengths[a] << "\n";
  out << "ITEM: ATOMS id type radius x y z mass\n";
  for (std::size_t k = p.size(); k-- > 0;) {
    out << k + 1 << " 1 " << p.radii[k];
    for (int a = 0; a < 3; ++a) out << " " << p.positions(static_cast<Eigen::Index>(k), a);
    out << " 1\n";
  }
}

TEST(Probe, ExportedDataFileAndDumpsGiveTheSamePackingAndEnvelopes) {
  const fs::path base = tiny();
  const fs::path dir = rendulic::testing::fresh_dir("app_probe/round_trip");
  const fs::path data = dir / "a.data", dump = dir / "a.dump";
  const CliResult exported =
      run_rendulic("export " + base.string() + " --state a --lammps " + data.string(), false);
  ASSERT_EQ(exported.code, 0) << exported.err;
  // The run's material (<r>, w), which the packing files do not carry: as export says to give
  // it, the sample's mean radius being another (1.4 % here, and so every starred number).
  const std::string say = "rendulic probe " + data.string();
  const std::size_t at = exported.err.find(say);
  ASSERT_NE(at, std::string::npos) << exported.err;
  const std::string sets =
      exported.err.substr(at + say.size(), exported.err.find('\n', at) - at - say.size());
  EXPECT_EQ(sets, " --set material.r_mean=0.001 --set material.w=3") << exported.err;
  write_dump(rendulic::read_lammps_data(data), dump);
  // The same dump declaring another unit style: read as SI, with a warning that says so.
  std::ofstream(dir / "lj.dump") << "ITEM: UNITS\nlj\n" << std::ifstream(dump).rdbuf();
  std::vector<fs::path> inputs = {data, dump, dir / "lj.dump"};
  if (rendulic::testing::have_lammps()) {
    std::ofstream(dir / "in.dump") << "units si\natom_style sphere\nboundary p p p\n"
                                      "read_data a.data\nwrite_dump all custom lammps.dump id "
                                      "diameter x y z modify sort id format float %.17g "
                                      "units yes time yes\n";
    const CliResult l = run_command("cd " + dir.string() + " && lmp -nocite -log none -in in.dump");
    ASSERT_EQ(l.code, 0) << l.out;
    inputs.push_back(dir / "lammps.dump");
  }
  const std::string common = " --methods linear_response --directions 12 ";
  const CliResult rs = probe(base.string() + ":a" + common + "--out " + (dir / "from_h5").string());
  ASSERT_EQ(rs.code, 0) << rs.err;
  const ResultsReader ref(dir / "from_h5" / "results.h5");
  const std::string ga = paths::state("a"), gi = paths::state("imported");
  const ResultsReader stored(base);
  for (const fs::path& in : inputs) {
    SCOPED_TRACE(in.string());
    const fs::path out = dir / ("from_" + in.filename().string());
    const CliResult r = probe(in.string() + common + sets + " --out " + out.string());
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_EQ(r.err.find("its units are 'lj'; its lengths are read as metres") != std::string::npos,
              in.filename() == "lj.dump")
        << r.err;
    const ResultsReader got(out / "results.h5");
    // The same packing, taken as it was: at rest as read.
    EXPECT_TRUE(got.read_matrix(gi + ds::kPositions) == stored.read_matrix(ga + ds::kPositions));
    EXPECT_EQ(got.read_vector(gi + ds::kRadii), stored.read_vector(ga + ds::kRadii));
    EXPECT_EQ(got.attr_int(gi, "minimise_iterations"), 0);
    EXPECT_EQ(got.attr_string(gi, "source").find(in.string()), 0u);
    for (const std::string& name : ref.children(paths::envelopes(ga)))
      expect_same_envelope(ref, paths::envelope(ga, name), got, paths::envelope(gi, name), 1e-12);
  }
}

TEST(Probe, APackingAwayFromEquilibriumIsBroughtToRestAndSaysWhatMoved) {
  const fs::path base = tiny();
  const fs::path dir = rendulic::testing::fresh_dir("app_probe/shaken");
  rendulic::Packing p = rendulic::read_results_state(base, paths::state("a"));
  // Every particle displaced by up to 2 % of <r>: contact forces no longer balance.
  for (Eigen::Index i = 0; i < p.positions.rows(); ++i)
    for (int a = 0; a < 3; ++a)
      p.positions(i, a) += 2e-5 * std::sin(1.7 * static_cast<double>(3 * i + a));
  rendulic::write_lammps_data(dir / "shaken.data", p, 2000, "shaken");
  const CliResult r = run_rendulic(
      "probe " + (dir / "shaken.data").string() +
          " --methods linear_response --directions 8 --threads 1 --out " + (dir / "out").string(),
      false);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("relaxing and minimising"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("particles moved more than"), std::string::npos) << r.err;
  const ResultsReader got(dir / "out" / "results.h5");
  const std::string g = paths::state("imported");
  EXPECT_LT(got.attr_double(g, "force_balance"), 1e-4);
  EXPECT_GT(got.attr_double(g, "force_balance_relaxed"), 0);
  EXPECT_GT(got.attr_double(g, "minimise_max_displacement"), 0);
  // Linear response and its fit: an ellipse per amplitude, semi-axes printed per unit strain.
  EXPECT_NE(r.out.find("linear_response_5e-05"), std::string::npos) << r.out;
}

// A packing at a saddle of its energy (a stable 250-sphere packing, nu = 0.70, seed 6, side by
// side with a copy of itself along y: 2 negative modes, dem's linear_response_test): probed as
// read, it has no linear response and the reason says it is a saddle; with --leave-saddle it is
// moved off to a minimum first, says how far, and has one.
TEST(Probe, ASaddleHasNoLinearResponseUntilItIsLeft) {
  const fs::path dir = rendulic::testing::fresh_dir("app_probe/saddle");
  rendulic::dem::GeneratedPackingOptions g;
  g.n = 250;
  g.volume_fraction = 0.70;
  g.seed = 6;
  g.minimise.force_tolerance = 1e-10;
  rendulic::dem::MinimiseSummary made;
  const rendulic::dem::PackingData one = rendulic::dem::generate_packing(g, &made);
  ASSERT_TRUE(made.converged) << made.message;
  rendulic::Packing two;
  two.lengths = one.cell.lengths();
  two.lengths[1] *= 2.0;
  two.positions.resize(2 * one.size(), 3);
  two.positions << one.positions, one.positions;
  two.positions.bottomRows(one.size()).col(1).array() += one.cell.lengths()[1];
  for (int copy = 0; copy < 2; ++copy)
    for (int i = 0; i < one.size(); ++i) two.radii.push_back(one.radii[i]);
  rendulic::write_lammps_data(dir / "doubled.data", two, 2000, "doubled");
  const std::string args = "probe " + (dir / "doubled.data").string() +
                           " --methods linear_response --directions 8 --threads 1 --out ";
  const CliResult as_read = run_rendulic(args + (dir / "as_read").string(), false);
  ASSERT_EQ(as_read.code, 0) << as_read.err;
  EXPECT_NE(as_read.err.find("a saddle of its energy, not a minimum"), std::string::npos)
      << as_read.err;
  EXPECT_NE(as_read.err.find("--leave-saddle"), std::string::npos) << as_read.err;
  const CliResult left = run_rendulic(args + (dir / "left").string() + " --leave-saddle", false);
  ASSERT_EQ(left.code, 0) << left.err;
  EXPECT_NE(left.err.find("a saddle of its energy with 2 negative mode(s): moved off"),
            std::string::npos)
      << left.err;
  EXPECT_EQ(left.err.find("no linear response"), std::string::npos) << left.err;
  EXPECT_NE(left.out.find("linear_response_5e-05"), std::string::npos) << left.out;
  const ResultsReader got(dir / "left" / "results.h5");
  const std::string g_state = paths::state("imported");
  EXPECT_EQ(got.attr_int(g_state, "saddle_negative_modes"), 2);
  EXPECT_GE(got.attr_int(g_state, "saddle_rounds"), 1);
  EXPECT_LT(got.attr_double(g_state, "force_balance"), 1e-4);
  EXPECT_FALSE(got.has_attr(paths::envelope(g_state, "linear_response_5e-05"), "error"));
}

// Exit 2, one line that names `what`, no results file.
// Probe planes (docs/probes.md "Probe planes: true-triaxial probes"): `--planes rendulic
// deviatoric` writes the Rendulic envelope under today's name, bit for bit the plain command's,
// and the deviatoric one under its own with the `plane` attribute; the report lists it apart
// from the claims. An unknown plane (on `probe`, and as the key of `run`) exits 2 with one
// line naming it and writes nothing.
TEST(Probe, DeviatoricEnvelopesBesideTheRendulicOnesUnderTheirOwnNames) {
  const fs::path base = tiny();
  const fs::path both = rendulic::testing::fresh_dir("app_probe/plane_both");
  const fs::path plain = rendulic::testing::fresh_dir("app_probe/plane_plain");
  const std::string state = base.string() + ":/states/b --label b --methods linear_response";
  // A comma list, as every other list option of rendulic takes (probe's were refused).
  CliResult r = probe(state + " --planes rendulic,deviatoric --out " + both.string());
  ASSERT_EQ(r.code, 0) << r.err;
  r = probe(state + " --out " + plain.string());
  ASSERT_EQ(r.code, 0) << r.err;
  const ResultsReader a(both / "results.h5"), b(plain / "results.h5");
  const std::string g = paths::state("b");
  const std::string rendulic = paths::envelope(g, "linear_response_5e-05");
  const std::string deviatoric = paths::envelope(g, "linear_response_deviatoric_5e-05");
  ASSERT_TRUE(a.exists(rendulic));
  ASSERT_TRUE(a.exists(deviatoric));
  EXPECT_FALSE(b.exists(deviatoric));
  EXPECT_EQ(a.attr_string(rendulic, "plane"), "rendulic");
  EXPECT_EQ(a.attr_string(deviatoric, "plane"), "deviatoric");
  EXPECT_EQ(a.read_tensors(rendulic + ds::kDStress), b.read_tensors(rendulic + ds::kDStress));
  EXPECT_EQ(a.read_pairs(rendulic + ds::kStressStar), b.read_pairs(rendulic + ds::kStressStar));
  // The deviatoric plane's directions start at axial compression (0 deg), the Rendulic
  // plane's at isotropic compression (35.26 deg).
  EXPECT_EQ(a.read_vector(deviatoric + ds::kThetaDeg).front(), 0.0);
  EXPECT_NEAR(a.read_vector(rendulic + ds::kThetaDeg).front(), 35.26, 0.01);
  EXPECT_TRUE(a.exists(deviatoric + paths::kFitStress));

  r = run_rendulic("report " + (both / "results.h5").string() + " --no-figures", false);
  ASSERT_EQ(r.code, 0) << r.err;
  std::ifstream in(both / "report.md");
  const std::string md{std::istreambuf_iterator<char>(in), {}};
  const std::size_t section = md.find("## Envelopes in other probe planes");
  ASSERT_NE(section, std::string::npos) << md;
  EXPECT_NE(
      md.find("| b | linear_response_deviatoric_5e-05 | deviatoric | linear_response", section),
      std::string::npos)
      << md;
}

TEST(Probe, UnknownPlaneExitsTwoWithOneLineAndWritesNothing) {
  const fs::path base = tiny();
  const fs::path out = rendulic::testing::fresh_dir("app_probe/plane_bad");
  const CliResult r = probe(
      base.string() + ":/states/b --label b --planes rendulic octahedral --out " + out.string());
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_EQ(rendulic::testing::error_lines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("octahedral"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("probes.planes"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out / "results.h5"));
  const fs::path run_out = rendulic::testing::fresh_dir("app_probe/plane_bad_run");
  const CliResult run =
      run_rendulic("run " + rendulic::testing::tiny_scenario(kRoot).string() + " --out " +
                       run_out.string() + " --set 'probes.planes=[\"meridian_200\"]'",
                   false);
  EXPECT_EQ(run.code, 2) << run.err;
  EXPECT_EQ(rendulic::testing::error_lines(run.err), 1) << run.err;
  EXPECT_NE(run.err.find("meridian_200"), std::string::npos) << run.err;
  EXPECT_FALSE(fs::exists(run_out / "results.h5"));
}

// A method, amplitude or plane given twice ran its campaign twice into one envelope group (two
// amplitudes that print alike in the group's name too): refused in one line, nothing written.
TEST(Probe, AMethodAmplitudeOrPlaneGivenTwiceIsRefused) {
  const fs::path base = tiny();
  const fs::path out = rendulic::testing::fresh_dir("app_probe/twice");
  for (const std::string& args :
       {std::string("--methods linear_response linear_response"),
        std::string("--methods linear_response --amplitudes 1e-4 1.000001e-4"),
        std::string("--methods linear_response --planes deviatoric deviatoric")}) {
    const CliResult r =
        probe(base.string() + ":/states/b --label b " + args + " --out " + out.string());
    EXPECT_EQ(r.code, 2) << args << "\n" << r.err;
    EXPECT_EQ(rendulic::testing::error_lines(r.err), 1) << r.err;
    EXPECT_NE(r.err.find("given twice"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(out / "results.h5"));
  }
}

// Probing a state of DIR/results.h5 into DIR replaced the run's file by the probes' one (one
// state's envelopes), exit 0: refused in one line, the file untouched.
TEST(Probe, OutputIntoTheResultsFileItReadsFromIsRefused) {
  const fs::path dir = rendulic::testing::fresh_dir("app_probe/into_itself");
  fs::copy_file(tiny(), dir / "results.h5");
  const std::string before = rendulic::testing::read_file(dir / "results.h5");
  const CliResult r = probe((dir / "results.h5").string() +
                            ":/states/b --methods linear_response --out " + dir.string());
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_EQ(rendulic::testing::error_lines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("is the file the packing is read from"), std::string::npos) << r.err;
  EXPECT_EQ(rendulic::testing::read_file(dir / "results.h5"), before);
  // Another folder is fine.
  EXPECT_EQ(probe((dir / "results.h5").string() + ":/states/b --methods linear_response --out " +
                  (dir / "elsewhere").string())
                .code,
            0);
}

// A results file's state restarts from its checkpoint as it is: its neighbour list (and, with
// friction, the springs kept per entry) fits the dem.skin it was made with only, and each of
// its numbers must be finite. Another skin was an internal error (exit 1), a force of inf a
// results file carrying it; both are one line naming the culprit, exit 2, nothing written.
TEST(Probe, AResultsFileStateWithAnotherSkinOrANonFiniteNumberIsRefused) {
  const fs::path base = tiny();
  const fs::path out = rendulic::testing::fresh_dir("app_probe/checkpoint_bad");
  const CliResult skin = probe(base.string() + ":/states/b --methods dynamic --set dem.skin=0.05" +
                               " --out " + (out / "skin").string());
  EXPECT_EQ(skin.code, 2) << skin.err;
  EXPECT_EQ(rendulic::testing::error_lines(skin.err), 1) << skin.err;
  EXPECT_NE(skin.err.find(base.string() + ":/states/b/checkpoint: "), std::string::npos)
      << skin.err;
  EXPECT_NE(skin.err.find("made with dem.skin = "), std::string::npos) << skin.err;
  EXPECT_NE(skin.err.find("not 0.05"), std::string::npos) << skin.err;
  EXPECT_FALSE(fs::exists(out / "skin" / "results.h5"));

  const fs::path copy = out / "nan.h5";
  fs::copy_file(base, copy);
  {
    H5::H5File h(copy.string(), H5F_ACC_RDWR);
    H5::DataSet d = h.openDataSet("/states/b/checkpoint/forces");
    std::vector<double> v(static_cast<std::size_t>(d.getSpace().getSimpleExtentNpoints()));
    d.read(v.data(), H5::PredType::NATIVE_DOUBLE);
    v[4] = std::numeric_limits<double>::infinity();
    d.write(v.data(), H5::PredType::NATIVE_DOUBLE);
  }
  const CliResult nan =
      probe(copy.string() + ":/states/b --methods dynamic --out " + (out / "nan").string());
  EXPECT_EQ(nan.code, 2) << nan.err;
  EXPECT_EQ(rendulic::testing::error_lines(nan.err), 1) << nan.err;
  EXPECT_NE(nan.err.find(copy.string() +
                         ":/states/b/checkpoint/forces holds a number that is not finite"),
            std::string::npos)
      << nan.err;
  EXPECT_FALSE(fs::exists(out / "nan" / "results.h5"));
}

void expect_refused(const std::string& name, const std::string& text, const std::string& what) {
  SCOPED_TRACE(name);
  const fs::path dir = rendulic::testing::fresh_dir("app_probe/bad_" + name);
  const fs::path f = dir / name;
  std::ofstream(f) << text;
  const CliResult r = probe(f.string() + " --out " + (dir / "out").string());
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_EQ(rendulic::testing::error_lines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find(what), std::string::npos) << "expected '" << what << "' in: " << r.err;
  EXPECT_FALSE(fs::exists(dir / "out" / "results.h5"));
}

std::string data_file(const std::string& box, const std::string& atoms_header,
                      const std::string& atoms) {
  return "title\n\n2 atoms\n1 atom types\n\n" + box + "\n" + atoms_header + "\n\n" + atoms;
}
const std::string kBox = "0 0.01 xlo xhi\n0 0.01 ylo yhi\n0 0.01 zlo zhi\n";

// Two spheres pressed together (overlap 1.9 radii), no backbone: not at rest, so relaxed and
// minimised until they part, and the log says no contact is left. Before, the balance, judged
// over non-rattlers, was 0: "at rest as read", and the minimisation's stress change was
// printed as 2e+306 of a pressure of 0. With no pressure the inertial number sets no rate:
// exit 2, nothing written.
TEST(Probe, SpheresPressedTogetherWithoutABackboneAreRelaxedApart) {
  const fs::path dir = rendulic::testing::fresh_dir("app_probe/pressed");
  std::ofstream(dir / "pressed.data")
      << data_file("0 1 xlo xhi\n0 1 ylo yhi\n0 1 zlo zhi\n", "Atoms # sphere",
                   "1 1 0.3 2000 0.2 0.2 0.2\n2 1 0.3 2000 0.2 0.2 0.21\n");
  const CliResult r = run_rendulic(
      "probe " + (dir / "pressed.data").string() + " --threads 1 --out " + (dir / "out").string(),
      false);
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_EQ(r.err.find("at rest as read"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("1 contact(s) but no rigid backbone: every particle is a rattler, so "
                       "nothing balances their forces; relaxing and minimising"),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("no contact is left (p = 0;"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("the state has no pressure"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "out" / "results.h5"));
}

TEST(Probe, BadPackingFilesExitTwoWithOneLine) {
  expect_refused(
      "noradius.dump",
      "ITEM: TIMESTEP\n0\nITEM: NUMBER OF ATOMS\n1\nITEM: BOX BOUNDS pp pp pp\n0 1\n0 1\n"
      "0 1\nITEM: ATOMS id type x y z\n1 1 0.5 0.5 0.5\n",
      "no radius or diameter column");
  expect_refused(
      "walls.dump",
      "ITEM: TIMESTEP\n0\nITEM: NUMBER OF ATOMS\n1\nITEM: BOX BOUNDS pp ff pp\n0 1\n0 1\n"
      "0 1\nITEM: ATOMS id radius x y z\n1 0.1 0.5 0.5 0.5\n",
      "periodic on every axis");
  // A damaged count: the reader asked for memory for 10^12 atoms before reading one (an
  // internal error, std::bad_alloc, exit 1).
  expect_refused(
      "count.dump",
      "ITEM: TIMESTEP\n0\nITEM: NUMBER OF ATOMS\n1000000000000\nITEM: BOX BOUNDS pp pp pp\n"
      "0 1\n0 1\n0 1\nITEM: ATOMS id radius x y z\n1 0.1 0.5 0.5 0.5\n",
      "the snapshot ends after 1 of 1000000000000 atoms");
  expect_refused("point.data",
                 data_file(kBox, "Atoms # sphere",
                           "1 1 0 2000 0.001 0.001 0.001\n2 1 0.002 2000 0.005 0.005 0.005\n"),
                 "a diameter of 0: not a sphere (point particles have 0)");
  // LAMMPS refuses it too; it was read, and only warned about as differing from
  // material.density.
  expect_refused("density.data",
                 data_file(kBox, "Atoms # sphere",
                           "1 1 0.002 -2000 0.001 0.001 0.001\n2 1 0.002 2000 0.005 0.005 0.005\n"),
                 "a density of -2000: a density is positive");
  expect_refused("degenerate.data",
                 data_file("0 0.01 xlo xhi\n0.01 0.01 ylo yhi\n0 0.01 zlo zhi\n", "Atoms # sphere",
                           "1 1 0.002 2000 0.001 0.001 0.001\n2 1 0.002 2000 0.005 0.005 0.005\n"),
                 "degenerate box: yhi <= ylo (0.01 <= 0.01)");
  // Each length finite, their product not: the volume fraction and the cell widths would be
  // NaN (a segmentation fault in the pair search before).
  expect_refused("huge.data",
                 data_file("0 1e300 xlo xhi\n0 1e300 ylo yhi\n0 1e300 zlo zhi\n", "Atoms # sphere",
                           "1 1 0.002 2000 0.001 0.001 0.001\n2 1 0.002 2000 0.005 0.005 0.005\n"),
                 "the box volume (the product of its lengths) is not a positive finite number");
  expect_refused("triclinic.data",
                 data_file(kBox + "0.001 0 0 xy xz yz\n", "Atoms # sphere",
                           "1 1 0.002 2000 0.001 0.001 0.001\n2 1 0.002 2000 0.005 0.005 0.005\n"),
                 "triclinic");
  expect_refused("nan.data",
                 data_file(kBox, "Atoms # sphere",
                           "1 1 0.002 2000 0.001 nan 0.001\n2 1 0.002 2000 0.005 0.005 0.005\n"),
                 "'nan' is not a finite decimal number");
  expect_refused(
      "atomic.data",
      data_file(kBox, "Atoms # atomic", "1 1 0.001 0.001 0.001\n2 1 0.005 0.005 0.005\n"),
      "atom_style atomic");
  expect_refused("atomic_unnamed.data",
                 data_file(kBox, "Atoms", "1 1 0.001 0.001 0.001\n2 1 0.005 0.005 0.005\n"),
                 "not atom_style sphere");
  // Spheres as large as the box: each overlaps its own periodic image.
  expect_refused("overlapping.data",
                 data_file(kBox, "Atoms # sphere",
                           "1 1 0.009 2000 0.001 0.001 0.001\n2 1 0.009 2000 0.005 0.005 0.005\n"),
                 "periodic cell too small");
  // Two atoms at one point: their force was NaN, "internal error: DEM integration diverged"
  // (exit 1).
  expect_refused("coincident.data",
                 data_file(kBox, "Atoms # sphere",
                           "1 1 0.002 2000 0.003 0.001 0.001\n2 1 0.002 2000 0.003 0.001 0.001\n"),
                 "coincident.data (LAMMPS data file): DEM system: particles 0 and 1 (counted "
                 "from 0 in the packing's order) are both at (0.003, 0.001, 0.001) m");
  expect_refused("duplicate.data",
                 data_file(kBox, "Atoms # sphere",
                           "1 1 0.002 2000 0.001 0.001 0.001\n1 1 0.002 2000 0.005 0.005 0.005\n"),
                 "appears twice");
  // An atom id that is not a number ends the section as a keyword line would: the message
  // names that line.
  expect_refused(
      "id_nan.data",
      data_file(kBox, "Atoms # sphere",
                "1 1 0.002 2000 0.001 0.001 0.001\nnan 1 0.002 2000 0.005 0.005 0.005\n"),
      "the Atoms section has 1 lines, the header 2 atoms; it ends at 'nan 1 0.002 2000 "
      "0.005 0.005 0.005'");
  expect_refused("short.data",
                 data_file(kBox, "Atoms # sphere", "1 1 0.002 2000 0.001 0.001 0.001\n"),
                 "the header 2 atoms");
  // A label that is not there, and groups that are not states, list the states that are. In a
  // pressure branch, the branch's states are listed, not the run's own (here the branch holds
  // a copy of state a only).
  const std::string t = tiny().string();
  const fs::path branched = kRoot / "branched.h5";
  fs::copy_file(tiny(), branched, fs::copy_options::overwrite_existing);
  {
    H5::H5File h(branched.string(), H5F_ACC_RDWR);
    h.createGroup(paths::kPressure).close();
    h.createGroup(paths::pressure_branch(0.7)).close();
    h.createGroup(paths::states(paths::pressure_branch(0.7))).close();
    ASSERT_GE(
        H5Ocopy(h.getId(), paths::state("a").c_str(), h.getId(),
                paths::state("a", paths::pressure_branch(0.7)).c_str(), H5P_DEFAULT, H5P_DEFAULT),
        0);
  }
  const std::string b = branched.string() + ":/pressure/nu0.7/states/";
  for (const auto& [state, words] : std::vector<std::pair<std::string, std::string>>{
           {t + ":nope", t + ": no state /states/nope; its states are a, b"},
           {t + ":/states/", t + ":/states/: not a state (it holds no positions and radii); its "
                                 "states are a, b"},
           {t + ":/material", t + ":/material: not a state (it holds no positions and radii); "
                                  "its states are a, b"},
           {b + "b", branched.string() + ": no state /pressure/nu0.7/states/b; the states of "
                                         "/pressure/nu0.7 are a"},
           {b + "a/envelopes", b + "a/envelopes: not a state (it holds no positions and radii); "
                                   "the states of /pressure/nu0.7 are a"}}) {
    const CliResult r = probe(state + " --out /tmp/never");
    EXPECT_EQ(r.code, 2) << state;
    EXPECT_EQ(r.err, "rendulic: " + words + "\n");
  }
  const CliResult missing = probe("/nonexistent/packing.data --out /tmp/never");
  EXPECT_EQ(missing.code, 2);
  EXPECT_NE(missing.err.find("/nonexistent/packing.data: no such file"), std::string::npos)
      << missing.err;
  // A folder, a device and a FIFO in the words every input file gets (core text_file.hpp); a
  // FIFO must not hang the command.
  const fs::path d = kRoot / "not-files";
  fs::create_directories(d);
  const fs::path fifo = d / "fifo.data";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600) == 0 || errno == EEXIST, true);
  for (const auto& [packing, words] : std::vector<std::pair<std::string, std::string>>{
           {d.string(), d.string() + ": is a folder, not a packing file"},
           {"/dev/zero",
            "/dev/zero: not a regular file (a packing file is a LAMMPS data or dump "
            "file, or FILE.h5:/states/LABEL)"},
           {fifo.string(), fifo.string() + ": not a regular file"}}) {
    const CliResult r = probe(packing + " --out /tmp/never");
    EXPECT_EQ(r.code, 2) << packing;
    EXPECT_NE(r.err.find(words), std::string::npos) << r.err;
  }
}

}  // namespace

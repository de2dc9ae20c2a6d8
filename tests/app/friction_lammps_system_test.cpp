// The frictional engine against LAMMPS (docs/interop.md "Friction against LAMMPS"): the same
// packing of 500 spheres (frictionless preparation, then at rest with no tangential history),
// written with the writer of `rendulic export`, deformed by the same short extension in both
// (LAMMPS: pair granular hooke + tangential linear_history with the settings
// dem::lammps_pair_lines gives, fix nve/sphere, fix deform erate with remap v and the affine
// velocities in the data file), and the stress histories compared; with rolling resistance
// (rolling sds) also the rotational kinetic energy. Skipped where Debian's `lmp` is not
// installed.
//
// Starting identically: the positions are those of the rendulic system (wrapped into the
// cell, 17 significant digits, read back to the same doubles), velocities zero relative to the
// imposed flow, no rotation, no tangential history, the same time step; no background damping
// in either (LAMMPS's fix viscous would damp the flow itself). The box grows linearly in time
// (erate: L = L0 (1 + R t)), along which particles moving with the flow need no force; rendulic
// follows the same lengths with the per-step rate D = ln(L_k+1 / L_k) / dt.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <vector>

#include "cli_runner.hpp"
#include "packing_system.hpp"
#include "rendulic/core/packing_file.hpp"
#include "rendulic/dem/protocols.hpp"

namespace {
namespace fs = std::filesystem;
using rendulic::testing::have_lammps;
using rendulic::testing::run_command;
namespace dem = rendulic::dem;

constexpr int kSteps = 2000, kEvery = 100;
const Eigen::Vector3d kRate(200.0, -100.0, -100.0);  // engineering strain rates, 1/s

// A packing at nu = 0.7 prepared as `rendulic bench` prepares its states (fast overdamped
// compression, relaxed), frictionless.
dem::DemSystem prepared() {
  dem::SystemOptions fast;
  fast.material.gamma_b = 10.0;
  dem::GasOptions g;
  g.n_particles = 500;
  g.velocity = 0.0;
  dem::DemSystem s = dem::make_gas(fast, g, 3);
  dem::CompressOptions c;
  c.target_nu = 0.7;
  c.rate_max = c.rate_min = 3000.0;
  dem::compress_isotropic(s, c);
  dem::RelaxOptions r;
  r.time_cap = 2e-5;
  dem::relax(s, r);
  return s;
}

using History = std::vector<Eigen::Matrix3d>;

// rendulic along the linear box growth; the stress every kEvery steps (step 0 included), and
// the rotational kinetic energy with it when `erot` is given.
History run_rendulic(dem::DemSystem s, std::vector<double>* erot = nullptr) {
  History h{s.measure().stress};
  if (erot) erot->assign(1, s.rotational_energy());
  for (int k = 0; k < kSteps; ++k) {
    const double t0 = k * s.dt(), t1 = (k + 1) * s.dt();
    Eigen::Vector3d D;
    for (int a = 0; a < 3; ++a) D[a] = std::log((1 + kRate[a] * t1) / (1 + kRate[a] * t0)) / s.dt();
    s.step(D);
    if ((k + 1) % kEvery == 0) {
      h.push_back(s.measure().stress);
      if (erot) erot->push_back(s.rotational_energy());
    }
  }
  return h;
}

double max_difference(const History& a, const History& b) {
  double m = 0;
  for (std::size_t k = 0; k < std::min(a.size(), b.size()); ++k)
    m = std::max(m, (a[k] - b[k]).cwiseAbs().maxCoeff());
  return m;
}

// LAMMPS along the same linear box growth from system `a` (its positions, at rest relative to
// the flow), with the pair settings of `m`; the stress every kEvery steps, and the rotational
// kinetic energy into `erot`.
History run_lammps(const dem::DemSystem& a, const dem::Material& m, const std::string& name,
                   std::vector<double>* erot = nullptr) {
  const fs::path dir = rendulic::testing::fresh_dir("app_friction_lammps/" + name);
  rendulic::Packing p = rendulic::app::packing_of_system(a);
  const Eigen::Vector3d L = p.lengths;
  p.velocities.resize(p.positions.rows(), 3);
  for (Eigen::Index i = 0; i < p.positions.rows(); ++i)
    for (int c = 0; c < 3; ++c)  // fix deform keeps the box centre fixed
      p.velocities(i, c) = kRate[c] * (p.positions(i, c) - 0.5 * L[c]);
  rendulic::write_lammps_data(dir / "a.data", p, m.density, "friction check");
  std::ostringstream in;
  in << std::setprecision(17) << "units si\natom_style sphere\nboundary p p p\n"
     << "comm_modify vel yes\nread_data a.data\n"
     << dem::lammps_pair_lines(m) << "neighbor 3e-4 bin\n"
     << "neigh_modify delay 0 every 1 check yes\nfix 1 all nve/sphere\n"
     << "fix 2 all deform 1 x erate " << kRate[0] << " y erate " << kRate[1] << " z erate "
     << kRate[2] << " remap v\n"
     << "timestep " << a.dt() << "\n"
     << "compute sigma all pressure NULL virial\n"
     // The spheres' rotational kinetic energy, I = 2/5 m r^2 (Debian's LAMMPS has no
     // compute erot/sphere).
     << "compute spin all property/atom radius omegax omegay omegaz\n"
     << "variable erot_i atom 0.2*mass*c_spin[1]^2*(c_spin[2]^2+c_spin[3]^2+c_spin[4]^2)\n"
     << "compute erot all reduce sum v_erot_i\n"
     << "thermo_style custom step c_sigma[1]\nthermo " << kEvery << "\n"
     << "fix out all print " << kEvery
     << " \"S $(c_sigma[1]:%.17g) $(c_sigma[2]:%.17g) $(c_sigma[3]:%.17g) "
        "$(c_sigma[4]:%.17g) $(c_sigma[5]:%.17g) $(c_sigma[6]:%.17g) $(c_erot:%.17g)\" screen "
        "yes\n"
     << "run " << kSteps << "\n";
  std::ofstream(dir / "in.friction") << in.str();
  const auto l =
      run_command("cd " + dir.string() + " && lmp -nocite -log none -echo none -in in.friction");
  EXPECT_EQ(l.code, 0) << l.out;
  History theirs;
  std::istringstream lines(l.out);
  for (std::string line; std::getline(lines, line);) {
    if (line.rfind("S ", 0) != 0) continue;
    std::istringstream f(line.substr(2));
    double v[7];
    for (double& x : v) f >> x;
    if (erot) erot->push_back(v[6]);
    Eigen::Matrix3d s;
    s << v[0], v[3], v[4], v[3], v[1], v[5], v[4], v[5], v[2];  // xx yy zz xy xz yz
    theirs.push_back(s);
  }
  return theirs;
}

void print(const std::string& what, const History& ours, const History& theirs) {
  for (std::size_t k = 0; k < std::min(ours.size(), theirs.size()); k += 5)
    std::cout << "  " << what << " step " << k * kEvery << ": xx " << ours[k](0, 0) << " / "
              << theirs[k](0, 0) << ", yy " << ours[k](1, 1) << " / " << theirs[k](1, 1) << ", xy "
              << ours[k](0, 1) << " / " << theirs[k](0, 1) << "\n";
}

TEST(FrictionLammps, StressHistoryOfAShortExtensionMatchesLammps) {
  const dem::DemSystem base = prepared();
  dem::SystemOptions rough;
  rough.material.mu = 0.5;
  rough.material.gamma_b = 0.0;
  dem::SystemOptions smooth = rough;
  smooth.material.mu = 0.0;
  // Wrapped positions, at rest, no history: the state both engines start from.
  const rendulic::Packing start = rendulic::app::packing_of_system(base);
  const dem::DemSystem a = rendulic::app::system_of_packing(start, rough);
  const History ours = run_rendulic(a);
  const History frictionless = run_rendulic(rendulic::app::system_of_packing(start, smooth));
  const double p0 = ours.front().trace() / 3;
  ASSERT_GT(p0, 0);
  const Eigen::Matrix3d d_ours = ours.back() - ours.front();
  // Friction matters here: it changes the stress path by a sizeable part of its increment.
  const double friction_effect = max_difference(ours, frictionless);
  EXPECT_GT(friction_effect, 0.1 * d_ours.cwiseAbs().maxCoeff());

  if (!have_lammps()) GTEST_SKIP() << "lmp not installed: the LAMMPS comparison is skipped";
  const History theirs = run_lammps(a, rough.material, "sliding");
  ASSERT_EQ(theirs.size(), ours.size());
  const double diff = max_difference(ours, theirs);
  std::cout << "friction vs LAMMPS: p0 = " << p0 << " Pa, stress increment "
            << d_ours.cwiseAbs().maxCoeff() << " Pa, friction's effect " << friction_effect
            << " Pa, rendulic - LAMMPS " << diff << " Pa (max over components and " << ours.size()
            << " samples)\n";
  print("friction", ours, theirs);
  // Measured (Debian's LAMMPS 20220106): 5.4e5 Pa = 4e-4 p0 = 0.0034 of friction's effect, the
  // differences growing along the path (the engines differ in the velocities of the dashpots,
  // the levers of the rotational velocity and the turning of the springs, docs/interop.md, and
  // a packing amplifies any difference); at step 0 rendulic has no affine velocity yet (its
  // first step sets D), LAMMPS has: 7e-5 p0 there.
  EXPECT_LT(diff, 0.02 * friction_effect);
  EXPECT_LT(diff, 2e-3 * p0);
}

// Rolling resistance (docs/physics.md, LAMMPS's `rolling sds`) on the same packing and path.
// Its effect on the stress is small over this path, but it damps the particles' spin: the
// rotational kinetic energy, summed over the particles, is compared too. The normal damping
// is not 1 kg/s here, so that a rolling damping LAMMPS took as a multiple of it (as it takes
// the tangential one) would show; the rolling damping is raised for the same reason.
TEST(FrictionLammps, RollingResistanceMatchesLammps) {
  const dem::DemSystem base = prepared();
  dem::SystemOptions sliding;
  sliding.material.mu = 0.5;
  sliding.material.gamma_b = 0.0;
  sliding.material.gamma = 0.3;
  dem::SystemOptions rolling = sliding;
  rolling.material.mu_r = 0.1;
  rolling.material.gamma_r_ratio = 2.0;
  const rendulic::Packing start = rendulic::app::packing_of_system(base);
  const dem::DemSystem a = rendulic::app::system_of_packing(start, rolling);
  std::vector<double> erot, erot_without, erot_lammps, erot_lammps_without;
  const History ours = run_rendulic(a, &erot);
  const History without =
      run_rendulic(rendulic::app::system_of_packing(start, sliding), &erot_without);
  const double p0 = ours.front().trace() / 3;
  ASSERT_GT(p0, 0);
  double erot_effect = 0, erot_diff = 0, erot_diff_without = 0;
  for (std::size_t k = 0; k < erot.size(); ++k)
    erot_effect = std::max(erot_effect, std::abs(erot[k] - erot_without[k]));

  if (!have_lammps()) GTEST_SKIP() << "lmp not installed: the LAMMPS comparison is skipped";
  const History theirs = run_lammps(a, rolling.material, "rolling", &erot_lammps);
  run_lammps(a, sliding.material, "rolling_off", &erot_lammps_without);
  ASSERT_EQ(theirs.size(), ours.size());
  ASSERT_EQ(erot_lammps.size(), erot.size());
  for (std::size_t k = 0; k < erot.size(); ++k) {
    erot_diff = std::max(erot_diff, std::abs(erot[k] - erot_lammps[k]));
    erot_diff_without =
        std::max(erot_diff_without, std::abs(erot_without[k] - erot_lammps_without[k]));
  }
  const double diff = max_difference(ours, theirs);
  std::cout << "rolling vs LAMMPS: p0 = " << p0 << " Pa, rendulic - LAMMPS " << diff
            << " Pa; rotational energy: rolling's effect " << erot_effect
            << " J, rendulic - LAMMPS " << erot_diff << " J with rolling, " << erot_diff_without
            << " J without\n";
  for (std::size_t k = 0; k < erot.size(); k += 4)
    std::cout << "  step " << k * kEvery << ": E_rot " << erot[k] << " / " << erot_lammps[k]
              << " J (without rolling " << erot_without[k] << " / " << erot_lammps_without[k]
              << ")\n";
  print("rolling", ours, theirs);
  // Measured (Debian's LAMMPS 20220106): rolling halves the rotational energy (its effect
  // 0.0179 J); rendulic - LAMMPS 5.5e-4 J with rolling, 1.0e-3 J without (the engines' own
  // difference, as in the test above); with the rolling damping passed as a multiple of the
  // normal one, 4.5e-3 J. Stress: 5.9e5 Pa = 5e-4 p0.
  EXPECT_LT(diff, 2e-3 * p0);
  EXPECT_GT(erot_effect, 0.2 * *std::max_element(erot_without.begin(), erot_without.end()));
  EXPECT_LT(erot_diff, 0.05 * erot_effect);
}

}  // namespace

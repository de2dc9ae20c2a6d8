// States at rest (docs/dem.md "States at rest"): the equilibrium criterion against a closed
// form (a compressed FCC lattice, at rest and with one particle displaced), and a DEM state
// brought to rest: below the criterion's bound, its stress the one of its own positions, its
// strain and particles kept.
#include "rendulic/dem/rest.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "rendulic/dem/probe_campaign.hpp"

namespace rendulic::dem {
namespace {

constexpr double kK = 1e8;

// FCC lattice of `cells`^3 cubic cells (4 sites each), nearest-neighbour distance r0, radius R.
PackingData fcc(int cells, double r0, double radius) {
  const double a = r0 * std::numbers::sqrt2;
  const Eigen::Vector3d basis[4] = {{0, 0, 0}, {0.5, 0.5, 0}, {0.5, 0, 0.5}, {0, 0.5, 0.5}};
  const int n = 4 * cells * cells * cells;
  Eigen::MatrixX3d x(n, 3);
  int p = 0;
  for (int i = 0; i < cells; ++i)
    for (int j = 0; j < cells; ++j)
      for (int k = 0; k < cells; ++k)
        for (const auto& b : basis) x.row(p++) = (a * (Eigen::Vector3d(i, j, k) + b)).transpose();
  return PackingData::orthorhombic(x, Eigen::VectorXd::Constant(n, radius),
                                   Eigen::Vector3d::Constant(cells * a));
}

// The 12 nearest-neighbour vectors of an FCC site.
std::vector<Eigen::Vector3d> fcc_neighbours(double r0) {
  std::vector<Eigen::Vector3d> d;
  const double h = r0 / std::numbers::sqrt2;
  for (int s1 : {-1, 1})
    for (int s2 : {-1, 1}) {
      d.emplace_back(s1 * h, s2 * h, 0);
      d.emplace_back(s1 * h, 0, s2 * h);
      d.emplace_back(0, s1 * h, s2 * h);
    }
  return d;
}

TEST(ForceBalance, CompressedFccIsAtRest) {
  const double radius = 1e-3, r0 = 1.99e-3;
  const PackingData p = fcc(3, r0, radius);
  const ForceBalance b = force_balance(p, kK);
  EXPECT_EQ(b.non_rattlers, p.size());
  EXPECT_EQ(b.contacts, 6 * p.size());
  EXPECT_NEAR(b.mean_contact_force, kK * (2 * radius - r0), 1e-9 * kK * (2 * radius - r0));
  EXPECT_LT(b.ratio, 1e-12);
}

// One site moved by u: its net force is the sum over its 12 bonds of k (2R - |l|) l/|l| with
// l = u - d (the displaced site minus its neighbour); its neighbours feel one changed bond
// each, less than that sum. The mean force is over the 6N bonds, 12 of them changed.
TEST(ForceBalance, OneDisplacedSiteMatchesTheClosedForm) {
  const double radius = 1e-3, r0 = 1.99e-3;
  PackingData p = fcc(3, r0, radius);
  const Eigen::Vector3d u(2e-6, -1e-6, 0.5e-6);
  p.positions.row(13) += u.transpose();
  Eigen::Vector3d net = Eigen::Vector3d::Zero();
  double changed = 0.0;
  for (const Eigen::Vector3d& d : fcc_neighbours(r0)) {
    const Eigen::Vector3d l = u - d;
    const double f = kK * (2 * radius - l.norm());
    net += f * l / l.norm();
    changed += f;
  }
  const double n_bonds = 6.0 * p.size();
  const double mean = (changed + (n_bonds - 12) * kK * (2 * radius - r0)) / n_bonds;
  const ForceBalance b = force_balance(p, kK);
  EXPECT_NEAR(b.mean_contact_force, mean, 1e-12 * mean);
  EXPECT_NEAR(b.max_net_force, net.norm(), 1e-9 * net.norm());
  EXPECT_NEAR(b.ratio, net.norm() / mean, 1e-9 * net.norm() / mean);
  EXPECT_GT(b.ratio, 10 * kEquilibrium);  // 2e-6 of 1e-5 overlap: far from rest
}

// A jammed packing moved off its minimum and handed to the engine in motion: brought to rest,
// it is below the bound, and what the engine measures is the stress of its own positions.
TEST(BringToRest, ADisturbedPackingEndsAtAMinimumWithItsOwnStress) {
  GeneratedPackingOptions g;
  g.n = 250;
  g.volume_fraction = 0.80;
  g.seed = 3;
  g.minimise.force_tolerance = 1e-6;
  const PackingData packing = generate_packing(g, nullptr);
  Eigen::MatrixX3d x = packing.positions;
  for (int i = 0; i < x.rows(); ++i)  // a deterministic disturbance of ~1e-3 <r>
    x.row(i) += 1e-6 * Eigen::RowVector3d(std::sin(1.0 + i), std::cos(2.0 * i), std::sin(3.0 * i));
  std::vector<double> radii(packing.radii.data(), packing.radii.data() + packing.size());
  DemSystem sys = system_from_positions(x, radii, packing.cell.lengths(), SystemOptions{});
  sys.advance(50, Eigen::Vector3d(1.0, -0.5, -0.5));  // some strain, some motion
  const Eigen::Vector3d strain = sys.strain_E();
  const ForceBalance before = force_balance(packing_of(sys), kK);
  RestOptions o;
  o.relax.time_cap = 1e-6;  // the dynamic part stops early: the minimisation must do the rest
  const RestSummary s = bring_to_rest(sys, o);
  EXPECT_GT(before.ratio, 1e-3);
  EXPECT_TRUE(s.minimised.converged) << s.minimised.message;
  EXPECT_LT(s.at_rest.ratio, 1e-8);
  EXPECT_LT(s.at_rest.ratio, kEquilibrium);
  // The state is its minimum: the criterion from its positions, its measured stress and
  // fabric those of the same positions by the independent geometry of probe_geometry.
  const PackingData rest = packing_of(sys);
  EXPECT_EQ(force_balance(rest, kK).ratio, s.at_rest.ratio);
  const StressFabric sf = measure_stress_fabric(rest, kK);
  const Measures m = sys.measure();
  EXPECT_LE((m.stress - sf.stress).norm(), 1e-10 * sf.stress.norm());
  EXPECT_LE((m.fabric - sf.fabric).norm(), 1e-12 * sf.fabric.norm());
  EXPECT_EQ(m.kinetic_energy, 0.0);
  EXPECT_EQ(sys.strain_E(), strain);
  for (std::size_t i = 0; i < radii.size(); ++i) {  // wrapped into the cell
    EXPECT_GE(sys.particles().x[i], 0.0);
    EXPECT_LT(sys.particles().x[i], sys.cell().lengths()[0]);
  }
  // Continuing from there: nothing moves (forces of 1e-9 of the mean contact force).
  DemSystem again = sys;
  again.advance(200, Eigen::Vector3d::Zero());
  EXPECT_LT(again.kinetic_energy(), 1e-14 * again.elastic_energy());
}

// Round-off bounds the net forces from below (about 1e-14 of the mean contact force here): a
// tolerance under that floor ran FIRE for all its iterations (20 s at N = 100, minutes at the
// paper's N) and then failed as "not converged", an internal error of the states stage. FIRE
// now stops where the floor stalls it and the refusal names the key and a tolerance it meets.
TEST(MinimiseEnergy, AToleranceBelowTheRoundOffFloorStallsEarlyAndSaysSo) {
  const PackingData start =
      generate_packing({.n = 100, .volume_fraction = 0.75, .seed = 2}, nullptr);
  MinimiseOptions o;
  o.force_tolerance = 1e-16;
  PackingData p = start;
  const MinimiseSummary s = minimise_energy(p, o);
  EXPECT_FALSE(s.converged);
  EXPECT_GT(s.stalled_at, o.force_tolerance) << s.message;
  EXPECT_LT(s.stalled_at, 1e-12) << s.message;
  EXPECT_LT(s.iterations, o.max_iterations / 5) << s.message;
  EXPECT_NE(s.message.find("FIRE stalled at"), std::string::npos) << s.message;
  const std::string why = round_off_refusal(s, "states.force_tolerance", o.force_tolerance);
  EXPECT_EQ(why.rfind("states.force_tolerance = 1e-16 is below the round-off floor", 0), 0u) << why;
  // The tolerance it names is met from the same start, with no stall.
  const double named = std::stod(why.substr(why.rfind("use ") + 4));
  EXPECT_GE(named, 10 * s.stalled_at) << why;
  EXPECT_LE(named, 100 * s.stalled_at) << why;
  o.force_tolerance = named;
  p = start;
  const MinimiseSummary met = minimise_energy(p, o);
  EXPECT_TRUE(met.converged) << met.message;
  EXPECT_EQ(met.stalled_at, 0.0);
}

}  // namespace
}  // namespace rendulic::dem

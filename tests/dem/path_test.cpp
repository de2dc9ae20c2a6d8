// Records of the strain-controlled protocols (docs/dem.md): every sample carries the inertial
// number of the imposed rate at that sample's pressure, I = rate 2<r> sqrt(rho / P), also on
// the steps shortened to land on samples and snapshots; the loading's snapshots land exactly
// on their volume fractions without changing the loading; window means and their batch-means
// standard errors.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "rendulic/core/errors.hpp"
#include "rendulic/dem/probe_minimise.hpp"
#include "rendulic/dem/protocols.hpp"

namespace rendulic::dem {
namespace {

DemSystem jammed(double nu) {
  GeneratedPackingOptions g;
  g.n = 250;
  g.volume_fraction = nu;
  g.seed = 2;
  g.minimise.force_tolerance = 1e-6;
  const PackingData p = generate_packing(g, nullptr);
  std::vector<double> radii(p.radii.data(), p.radii.data() + p.size());
  return system_from_positions(p.positions, radii, p.cell.lengths(), SystemOptions{});
}

double expected_inertial(const Material& m, double rate, double pressure) {
  return rate * 2.0 * m.r_mean * std::sqrt(m.density / pressure);
}

TEST(PathRecords, InertialNumberIsTheImposedRatesAtEverySample) {
  DemSystem sys = jammed(0.78);
  PathOptions o;
  o.rate = 3000.0;
  o.eps_dev_max = 1e-3;
  o.samples = 7;  // 1.67e-4 apart: not a whole number of steps, so steps are shortened
  o.snapshot_eps_dev = {3.3e-4};
  std::vector<Measures> rows;
  undrained_extension(sys, o, [&](const Measures& m) { rows.push_back(m); });
  ASSERT_EQ(rows.size(), 7u);
  EXPECT_EQ(rows[0].inertial_number, 0.0);  // the state at rest before the path
  for (std::size_t k = 1; k < rows.size(); ++k) {
    const double want = expected_inertial(sys.material(), o.rate, rows[k].pressure);
    EXPECT_NEAR(rows[k].inertial_number, want, 1e-12 * want) << k;
    EXPECT_EQ(rows[k].strain_rate, o.rate) << k;
  }
}

TEST(PathRecords, LoadingSnapshotsLandOnTheirVolumeFractions) {
  DemSystem sys = jammed(0.70);
  CompressOptions o;
  o.target_nu = 0.705;
  o.rate_max = o.rate_min = 2000.0;
  o.samples = 4;
  o.snapshot_nu = {0.7031, 0.7017};  // any order
  std::vector<Measures> rows;
  const CompressSummary s =
      compress_isotropic(sys, o, [&](const Measures& m) { rows.push_back(m); });
  ASSERT_EQ(s.snapshots.size(), 2u);
  EXPECT_NEAR(s.snapshots[0].volume_fraction(), 0.7017, 1e-12);
  EXPECT_NEAR(s.snapshots[1].volume_fraction(), 0.7031, 1e-12);
  EXPECT_NEAR(sys.volume_fraction(), 0.705, 1e-12);
  ASSERT_EQ(rows.size(), 4u);
  for (std::size_t k = 1; k < rows.size(); ++k) {
    const double want = expected_inertial(sys.material(), o.rate_max, rows[k].pressure);
    EXPECT_NEAR(rows[k].inertial_number, want, 1e-12 * want) << k;
  }
  // The loading itself is the one without snapshots, bit for bit.
  DemSystem plain = jammed(0.70);
  CompressOptions p = o;
  p.snapshot_nu.clear();
  compress_isotropic(plain, p);
  EXPECT_EQ(plain.steps(), sys.steps());
  EXPECT_EQ(plain.particles().x, sys.particles().x);
  EXPECT_EQ(plain.stress(), sys.stress());
  o.snapshot_nu = {0.71};  // beyond the target
  DemSystem again = jammed(0.70);
  EXPECT_THROW(compress_isotropic(again, o), InputError);
}

TEST(WindowMean, MeanAndBatchStandardError) {
  std::vector<double> x, y;
  for (int i = 0; i < 101; ++i) x.push_back(0.01 * i), y.push_back(2.0 + 0.5 * (0.01 * i));
  // A linear trend: the window mean is the value at the window's centre.
  const WindowMean w = window_mean(x, y, 0.2, 0.6, 4);
  EXPECT_EQ(w.samples, 41);
  EXPECT_NEAR(w.mean, 2.0 + 0.5 * 0.4, 1e-12);
  EXPECT_TRUE(w.ok);
  // Independent noise of standard deviation 1: the standard error of the mean is about
  // 1 / sqrt(n) (batch means of independent samples), here within 35 % for 10 batches.
  std::mt19937_64 rng(7);
  std::normal_distribution<double> noise(0.0, 1.0);
  std::vector<double> xs, ys;
  for (int i = 0; i < 4000; ++i) xs.push_back(i), ys.push_back(noise(rng));
  const WindowMean n = window_mean(xs, ys, 0, 4000, 10);
  EXPECT_NEAR(n.standard_error, 1.0 / std::sqrt(4000.0), 0.35 / std::sqrt(4000.0));
  EXPECT_LT(std::abs(n.mean), 4 * n.standard_error);
  // Too few samples for the batches: no error bar, and it says so.
  const WindowMean few = window_mean(x, y, 0.2, 0.25, 5);
  EXPECT_FALSE(few.ok);
  EXPECT_EQ(few.standard_error, 0.0);
  EXPECT_EQ(few.samples, 6);
}

}  // namespace
}  // namespace rendulic::dem

namespace rendulic::dem {
namespace {
// A relaxation's progress (protocols.hpp): the decay of kinetic/elastic on a log scale, or the
// time spent, whichever is further; a decay from 1e-2 to 1e-6 halfway (1e-4) is 0.5.
TEST(RelaxProgress, CountsTheDecayOnALogScaleOrTheTimeWhicheverIsFurther) {
  EXPECT_NEAR(relax_fraction(1e-2, 1e-4, 1e-6, 0.1), 0.5, 1e-12);
  EXPECT_NEAR(relax_fraction(1e-2, 1e-2, 1e-6, 0.3), 0.3, 1e-12);
  EXPECT_EQ(relax_fraction(1e-2, 1e-7, 1e-6, 0.0), 1.0);
  EXPECT_EQ(relax_fraction(1e-2, 1e-1, 1e-6, 0.0), 0.0);  // a transient rise: no progress
  EXPECT_EQ(relax_fraction(1e-8, 1e-8, 1e-6, 0.2), 1.0);  // already below the target
  EXPECT_EQ(relax_fraction(1e-2, 1e-4, 1e-6, 1.5), 1.0);  // the cap is the end
}
}  // namespace
}  // namespace rendulic::dem

// Records of the strain-controlled protocols (docs/dem.md): every sample carries the inertial
// number of the imposed rate at that sample's pressure, I = rate 2<r> sqrt(rho / P), also on
// the steps shortened to land on samples and snapshots; the loading's snapshots land exactly
// on their volume fractions without changing the loading; window means and their batch-means
// standard errors; a path and the isotropic loading that hold an inertial number; a rate too
// slow for any run refused.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>

#include "comma_locale.hpp"
#include "input_error.hpp"
#include "rendulic/core/conventions.hpp"
#include "rendulic/core/errors.hpp"
#include "rendulic/dem/probe_minimise.hpp"
#include "rendulic/dem/protocols.hpp"

namespace rendulic::dem {
namespace {

using rendulic::testing::input_error;

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
  run_path(sys, o, [&](const Measures& m) { rows.push_back(m); });
  ASSERT_EQ(rows.size(), 7u);
  EXPECT_EQ(rows[0].inertial_number, 0.0);  // the state at rest before the path
  for (std::size_t k = 1; k < rows.size(); ++k) {
    const double want = expected_inertial(sys.material(), o.rate, rows[k].pressure);
    EXPECT_NEAR(rows[k].inertial_number, want, 1e-12 * want) << k;
    EXPECT_EQ(rows[k].strain_rate, o.rate) << k;
  }
}

// A path that holds an inertial number takes its rate from the pressure, between rate_min and
// rate: the samples record that rate, and the inertial number it gives at their pressure is the
// target up to the pressure's change over the few steps between rate updates.
TEST(PathRecords, AHeldInertialNumberTakesItsRateFromThePressure) {
  const DemSystem start = jammed(0.78);
  const Material& m = start.material();
  const double P0 = start.stress().trace() / 3.0;
  // The inverse of I(rate, P), checked against the independent formula above.
  EXPECT_NEAR(expected_inertial(m, rate_for_inertial_number(m, 3e-4, P0), P0), 3e-4, 1e-18);
  EXPECT_EQ(rate_for_inertial_number(m, 3e-4, 0.0), 0.0);
  PathOptions o;
  o.type = "undrained_compression";
  o.rate = 6000.0;
  o.rate_min = 100.0;
  o.eps_dev_max = 1e-3;
  o.samples = 7;
  o.snapshot_eps_dev = {3.3e-4};
  o.inertial_number = expected_inertial(m, 2000.0, P0);  // 2000 1/s at the start
  DemSystem sys = start;
  std::vector<Measures> rows;
  const PathSummary p = run_path(sys, o, [&](const Measures& r) { rows.push_back(r); });
  ASSERT_EQ(rows.size(), 7u);
  for (std::size_t k = 1; k < rows.size(); ++k) {
    EXPECT_GT(rows[k].strain_rate, o.rate_min) << k;
    EXPECT_LT(rows[k].strain_rate, o.rate) << k;
    EXPECT_NEAR(rows[k].inertial_number, o.inertial_number, 0.02 * o.inertial_number) << k;
  }
  EXPECT_NEAR(rows.back().eps_dev, 1e-3, 1e-12);  // events still land exactly
  EXPECT_NEAR(p.snapshots[0].strain_E().norm(), 3.3e-4, 1e-14);
  // The pressure changed along the path, and the rate with it.
  EXPECT_NE(rows[1].strain_rate, rows.back().strain_rate);
  // The bounds: a target beyond what `rate` gives runs at `rate`, one below rate_min at it.
  for (const auto& [target, want] : {std::pair{10.0 * o.inertial_number, o.rate},
                                     std::pair{1e-3 * o.inertial_number, o.rate_min}}) {
    PathOptions b = o;
    b.inertial_number = target;
    b.eps_dev_max = 2e-4;
    b.snapshot_eps_dev = {};
    b.samples = 3;
    DemSystem again = start;
    std::vector<Measures> r;
    run_path(again, b, [&](const Measures& x) { r.push_back(x); });
    for (std::size_t k = 1; k < r.size(); ++k) EXPECT_EQ(r[k].strain_rate, want) << target;
  }
}

// The isotropic loading holds its inertial number the same way, from the pressure that the
// step before each rate update summed in its own force loop (step_measuring_stress): at every
// sample the recorded rate gives the target at the sample's pressure, to the pressure's change
// over those few steps. A pressure not measured there (the engine's last sum, from long ago,
// or none: 0) would leave the rate at rate_min.
TEST(PathRecords, TheIsotropicLoadingTakesItsRateFromThePressureOfItsOwnSteps) {
  DemSystem sys = jammed(0.70);
  const Material& m = sys.material();
  const double P0 = sys.stress().trace() / 3.0;
  CompressOptions o;
  o.target_nu = 0.705;
  o.rate_max = 6000.0;
  o.rate_min = 100.0;
  o.samples = 5;
  o.inertial_number = expected_inertial(m, 2000.0, P0);  // 2000 1/s at the start
  std::vector<Measures> rows;
  const CompressSummary s =
      compress_isotropic(sys, o, [&](const Measures& r) { rows.push_back(r); });
  ASSERT_EQ(rows.size(), 5u);
  EXPECT_GT(s.steps, 100);  // several rate updates
  for (std::size_t k = 1; k < rows.size(); ++k) {
    EXPECT_GT(rows[k].strain_rate, o.rate_min) << k;
    EXPECT_LT(rows[k].strain_rate, o.rate_max) << k;
    EXPECT_NEAR(rows[k].inertial_number, o.inertial_number, 0.01 * o.inertial_number) << k;
  }
  EXPECT_GT(rows[rows.size() - 2].pressure, 1.01 * P0);  // the pressure, and the rate, moved
  EXPECT_NE(rows[1].strain_rate, rows[rows.size() - 2].strain_rate);
  EXPECT_NEAR(sys.volume_fraction(), 0.705, 1e-12);
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

// The named paths (docs/dem.md "Paths"): each imposes the D it names, exactly, and ends at its
// strain s; the mixed ones hold their lateral stress target with the integral servo.
PathOptions short_path(const std::string& type, double s_max) {
  PathOptions o;
  o.type = type;
  o.rate = 2000.0;
  o.eps_dev_max = s_max;
  o.samples = 11;
  o.snapshot_eps_dev = {0.5 * s_max};
  return o;
}

TEST(Paths, UndrainedCompressionKeepsTheVolumeAndEndsAtItsDeviatoricStrain) {
  DemSystem sys = jammed(0.72);
  const double V0 = sys.volume();
  std::vector<Measures> rows;
  const PathSummary p = run_path(sys, short_path("undrained_compression", 2e-3),
                                 [&](const Measures& m) { rows.push_back(m); });
  EXPECT_NEAR(sys.volume(), V0, 1e-13 * V0);
  const Eigen::Vector3d E = sys.strain_E();
  // Axial compression: E = -e (1, -1/2, -1/2), |E| = s, signed eps_dev = +s.
  EXPECT_LT(E[0], 0);
  EXPECT_NEAR(E[1], -0.5 * E[0], 1e-15);
  EXPECT_NEAR(E.norm(), 2e-3, 1e-14);
  ASSERT_EQ(rows.size(), 11u);
  EXPECT_NEAR(rows.back().eps_dev, 2e-3, 1e-12);
  EXPECT_NEAR(p.snapshots[0].strain_E().norm(), 1e-3, 1e-14);
  EXPECT_EQ(p.servo_error, 0.0);
}

// A rate so slow that the path (or a probe's strain increment) would need more than
// kMaxSteps steps is refused up front, naming the key: the step count overflowed its integer
// before (path.rate = 1e-300 said "did not reach s in -9223372036854775608 steps").
TEST(Paths, ARateNeedingMoreThanKMaxStepsIsRefusedNamingIt) {
  DemSystem sys = jammed(0.72);
  PathOptions slow = short_path("undrained_compression", 2e-3);
  slow.rate = 1e-300;
  const std::string why = input_error([&] { run_path(sys, slow); });
  EXPECT_NE(why.find("path.rate needs "), std::string::npos) << why;
  EXPECT_NE(why.find("time steps, more than 1e+15"), std::string::npos) << why;
  const std::string inc =
      input_error([&] { impose_strain_increment(sys, Eigen::Vector3d(1e-3, 0.0, 0.0), 1e-300); });
  EXPECT_NE(inc.find("strain increment at this rate needs "), std::string::npos) << inc;
  EXPECT_EQ(step_count(12.0, "x"), 12);
  EXPECT_NE(input_error([] { step_count(std::nan(""), "x"); }).find("x needs nan"),
            std::string::npos);
}

// The isotropic compression too (preparation and isotropic loading to a volume fraction): a
// stiffness of 1e300 kg/s^2 gives dt ~ 1e-154 s, and `rendulic run` ran its preparation for
// ever. The fewest steps the loading can take (at rate_max) are judged before the first.
TEST(Paths, ACompressionNeedingMoreThanKMaxStepsIsRefusedNamingItsRate) {
  SystemOptions stiff;
  stiff.material.k = 1e300;
  GasOptions g;
  g.n_particles = 50;
  g.volume_fraction = 0.3;
  DemSystem sys = make_gas(stiff, g, 1);
  const std::int64_t steps = sys.steps();
  CompressOptions c;
  c.rate_key = "isotropic.rate_max";
  const std::string why = input_error([&] { compress_isotropic(sys, c); });
  EXPECT_NE(why.find("isotropic compression from nu = 0.3 to 0.64 at isotropic.rate_max = 1000 "
                     "1/s (dt = "),
            std::string::npos)
      << why;
  EXPECT_NE(why.find("time steps, more than 1e+15"), std::string::npos) << why;
  EXPECT_EQ(sys.steps(), steps);  // refused before the first step
  // At the default stiffness a loading runs.
  DemSystem soft = make_gas(SystemOptions{}, g, 1);
  c.target_nu = 0.31;
  EXPECT_NO_THROW(compress_isotropic(soft, c));
  // A loading to a pressure is judged by its span to the bound: it may stop earlier, but not in
  // 1e15 steps of 1e-300 of the span each (isotropic.rate_max = 1e-300 1/s ran for ever).
  CompressOptions to_p;
  to_p.rate_key = "isotropic.rate_max";
  to_p.target_pressure_star = 1e-3;
  to_p.target_nu = 0.75;
  to_p.rate_max = to_p.rate_min = 1e-300;
  DemSystem gas = make_gas(SystemOptions{}, g, 1);
  int checks = 0;  // without the refusal the loading would run for ever: stop it instead
  const auto bounded = [&](double) {
    if (++checks > 1000) throw std::runtime_error("the loading to P* was not refused");
  };
  const std::string why_p = input_error([&] { compress_isotropic(gas, to_p, nullptr, bounded); });
  EXPECT_NE(why_p.find("isotropic compression from nu = 0.3 to its bound 0.75 (loading to P* = "
                       "0.001) at isotropic.rate_max = 1e-300 1/s (dt = "),
            std::string::npos)
      << why_p;
  EXPECT_EQ(gas.steps(), steps);
  // A packing already at its P* ends at the first check, however slow the rate.
  DemSystem dense = jammed(0.70);
  to_p.target_pressure_star = 0.1 * pressure(dense.stress()) / dense.material().k_star();
  EXPECT_GT(to_p.target_pressure_star, 0.0);
  CompressSummary done;
  EXPECT_NO_THROW(done = compress_isotropic(dense, to_p));
  EXPECT_LE(done.steps, 100);  // the pressure is checked every few steps
}

// The message's numbers keep their point under a Python session's decimal-comma locale (it read
// "needs 1,5e+16 time steps").
using StepCountInACommaLocale = CommaLocale;
TEST_F(StepCountInACommaLocale, TheRefusalKeepsItsPoint) {
  EXPECT_EQ(input_error([] { step_count(1.5e16, "path.rate"); }),
            "path.rate needs 1.5e+16 time steps, more than 1e+15");
}

TEST(Paths, IsotropicLoadingRaisesTheVolumeFractionByTheClosedForm) {
  DemSystem sys = jammed(0.70);
  const double nu0 = sys.volume_fraction();
  run_path(sys, short_path("isotropic_loading", 3e-3));
  // E = -e (1, 1, 1) with |E| = sqrt(3) e = s: V = V0 exp(-3e), nu = nu0 exp(sqrt(3) s).
  EXPECT_NEAR(sys.volume_fraction(), nu0 * std::exp(std::sqrt(3.0) * 3e-3), 1e-12);
  DemSystem back = jammed(0.70);
  run_path(back, short_path("isotropic_unloading", 3e-3));
  EXPECT_NEAR(back.volume_fraction(), nu0 * std::exp(-std::sqrt(3.0) * 3e-3), 1e-12);
}

TEST(Paths, ProportionalPathFollowsItsDirection) {
  DemSystem sys = jammed(0.72);
  PathOptions o = short_path("proportional", 2e-3);
  o.direction = {2.0, 0.0, -1.0};  // plane strain in y, scaled by its largest component
  run_path(sys, o);
  const Eigen::Vector3d E = sys.strain_E();
  EXPECT_EQ(E[1], 0.0);
  EXPECT_NEAR(E[0], -2.0 * E[2], 1e-15);
  EXPECT_NEAR(E.norm(), 2e-3, 1e-14);
  o.direction = {0.0, 0.0, 0.0};
  EXPECT_THROW(run_path(sys, o), InputError);
  o.type = "triaxial";
  const std::string what = input_error([&] { run_path(sys, o); });  // an unknown path type
  EXPECT_NE(what.find("drained_compression"), std::string::npos) << what;
}

TEST(Paths, DrainedCompressionHoldsTheLateralStress) {
  DemSystem sys = jammed(0.72);
  const double p0 = sys.stress().trace() / 3.0;
  std::vector<Measures> rows;
  // A quasi-static rate (the seed's 400 1/s) and 2 % of axial strain: the servo has its
  // start-up transient in the first tenth of the path and then holds the target.
  PathOptions o = short_path("drained_compression", 2e-2);
  o.rate = 400.0;
  const PathSummary p = run_path(sys, o, [&](const Measures& m) { rows.push_back(m); });
  // The axial strain is imposed exactly; the lateral stress follows the servo.
  EXPECT_NEAR(-sys.strain_E()[0], 2e-2, 1e-14);
  EXPECT_TRUE(p.servo_held) << p.servo_error;
  for (std::size_t k = 2; k < rows.size(); ++k) {
    EXPECT_NEAR(rows[k].stress(1, 1), p0, 0.01 * p0) << k;
    EXPECT_NEAR(rows[k].stress(2, 2), p0, 0.01 * p0) << k;
  }
  // Compression raises the axial stress (the packing starts slightly anisotropic).
  EXPECT_GT(rows.back().stress(0, 0) - rows.front().stress(0, 0), 0.05 * p0);
}

TEST(Paths, ConstantMeanStressPathHoldsP) {
  DemSystem sys = jammed(0.72);
  const double p0 = sys.stress().trace() / 3.0;
  std::vector<Measures> rows;
  PathOptions o = short_path("constant_p_extension", 2e-2);
  o.rate = 400.0;
  const PathSummary p = run_path(sys, o, [&](const Measures& m) { rows.push_back(m); });
  EXPECT_TRUE(p.servo_held) << p.servo_error;
  for (std::size_t k = 2; k < rows.size(); ++k)
    EXPECT_NEAR(rows[k].stress.trace() / 3.0, p0, 0.01 * p0) << k;
  EXPECT_NEAR(sys.strain_E()[0], 2e-2, 1e-14);
}

TEST(Paths, AProportionalServoLagsAndTheRunSaysSo) {
  // Without the integral term the servo trails the lateral rate the path demands by
  // D_lat / gain: with a low gain that is far beyond the tolerance, and it is reported.
  DemSystem sys = jammed(0.72);
  PathOptions o = short_path("drained_compression", 2e-2);
  o.rate = 400.0;
  o.servo_integral_gain = 0.0;
  o.servo_gain = 2e-3;  // x 1/t_c: ~1e4 1/s on this material
  const PathSummary p = run_path(sys, o);
  EXPECT_FALSE(p.servo_held);
  EXPECT_GT(p.servo_error, o.servo_tolerance);
}

TEST(Paths, LoadingToAPressureStopsThereAndTheRelaxationHoldsIt) {
  DemSystem sys = jammed(0.70);
  const double k_star = sys.material().k_star();
  const double p_start = sys.stress().trace() / 3.0 / k_star;
  CompressOptions o;
  o.target_nu = 0.75;  // the bound
  o.rate_max = o.rate_min = 400.0;
  o.samples = 5;
  o.target_pressure_star = 1.5 * p_start;
  std::vector<Measures> rows;
  compress_isotropic(sys, o, [&](const Measures& m) { rows.push_back(m); });
  ASSERT_FALSE(rows.empty());
  // Stopped within the few steps between pressure checks of the target, below the bound.
  EXPECT_GE(rows.back().pressure_star, o.target_pressure_star);
  EXPECT_LT(rows.back().pressure_star, 1.01 * o.target_pressure_star);
  EXPECT_LT(sys.volume_fraction(), 0.75);
  RelaxOptions r;
  r.kinetic_to_elastic = 1e-5;
  r.time_cap = 2e-3;
  const RelaxSummary held = relax_at_pressure(sys, o.target_pressure_star * k_star, r,
                                              PathOptions{}.servo(sys.material()));
  EXPECT_TRUE(held.converged);
  EXPECT_NEAR(sys.stress().trace() / 3.0 / k_star, o.target_pressure_star,
              kPressureHold * o.target_pressure_star);
  // A pressure beyond the bound is refused, naming it.
  DemSystem again = jammed(0.70);
  o.target_nu = 0.701;
  o.target_pressure_star = 10 * p_start;
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

// The elastic range (docs/probes.md "Elastic range") of a packing whose response is known in
// closed form at any amplitude: a compressed FCC lattice, which deforms affinely (every site
// is a centre of inversion), so a probe's stress is that of the affinely strained lattice,
// sigma = (N / V') sum_bonds k (2R - |A d|)^+ |A d| n n with A = exp(-eps), n = A d / |A d|.
// Its bonds in the yz plane open under the constant-volume axial compression 125.26 (the
// reverse of the path), which stretches them by |eps| / sqrt 6, at |eps| = sqrt 6 ln(2R / r0);
// up to there the response departs from the linear one by the geometric non-linearity only,
// then it softens. The stage's numbers (dynamic probes of the
// DEM engine and minimisation probes) must equal the closed form's, and so its yield strain.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "rendulic/core/conventions.hpp"
#include "rendulic/dem/probe_campaign.hpp"
#include "rendulic/dem/probe_elastic_range.hpp"

namespace rendulic::dem {
namespace {

constexpr double kR = 1e-3, kR0 = 1.99e-3, kK = 1e8;
constexpr int kCells = 3;

DemSystem fcc_state(double r0 = kR0) {
  const double a = r0 * std::numbers::sqrt2;
  const Eigen::Vector3d basis[4] = {{0, 0, 0}, {0.5, 0.5, 0}, {0.5, 0, 0.5}, {0, 0.5, 0.5}};
  const int n = 4 * kCells * kCells * kCells;
  Eigen::MatrixXd x(n, 3);
  int p = 0;
  for (int i = 0; i < kCells; ++i)
    for (int j = 0; j < kCells; ++j)
      for (int k = 0; k < kCells; ++k)
        for (const auto& b : basis) x.row(p++) = (a * (Eigen::Vector3d(i, j, k) + b)).transpose();
  return system_from_positions(x, std::vector<double>(n, kR), Eigen::Vector3d::Constant(kCells * a),
                               SystemOptions{});
}

// Stress (Pa, compression positive) of the lattice strained affinely by eps.
Eigen::Matrix3d lattice_stress(const Eigen::Matrix3d& eps) {
  const double h = kR0 / std::numbers::sqrt2;
  const Eigen::Vector3d bonds[6] = {{h, h, 0},  {h, -h, 0}, {h, 0, h},
                                    {h, 0, -h}, {0, h, h},  {0, h, -h}};
  const Eigen::Matrix3d A = (-eps.diagonal()).array().exp().matrix().asDiagonal();
  const double n = 4.0 * kCells * kCells * kCells;
  const double volume = std::pow(kCells * kR0 * std::numbers::sqrt2, 3) * A.determinant();
  Eigen::Matrix3d s = Eigen::Matrix3d::Zero();
  for (const auto& d : bonds) {
    const Eigen::Vector3d l = A * d;
    const double f = kK * std::max(0.0, 2 * kR - l.norm());
    s += f * l.norm() * (l / l.norm()) * (l / l.norm()).transpose();
  }
  return n * s / volume;
}

// The elastic range of the closed form, by the stage's definitions (probe_elastic_range.hpp).
ElasticRange closed_form(const std::vector<double>& amplitudes, double tolerance) {
  const std::vector<double> theta = elastic_range_directions();
  // Elastic reference: the lattice's stiffness by central differences of the closed form.
  auto map_of = [&](double a) {
    std::vector<Eigen::Vector2d> strain, stress;
    for (double t : theta) {
      const Eigen::Matrix3d eps = probe_strain(t, a);
      strain.push_back(rendulic_pair(eps));
      stress.push_back(
          rendulic_pair(lattice_stress(eps) - lattice_stress(Eigen::Matrix3d::Zero())));
    }
    return std::make_pair(fit_rendulic_map(strain, stress), stress);
  };
  const RendulicMap el = map_of(1e-7).first;
  ElasticRange r;
  r.elastic_major = el.semi_major / 1e-7;
  r.elastic_minor = el.semi_minor / 1e-7;
  for (double a : amplitudes) {
    const auto [m, stress] = map_of(a);
    r.amplitude.push_back(a);
    r.minor_over_elastic.push_back(m.semi_minor / a / r.elastic_minor);
    r.major_over_elastic.push_back(m.semi_major / a / r.elastic_major);
    r.center_over_a.push_back(m.center.norm() / m.semi_major);
    auto k = [&](std::size_t p) {
      const double t = deg_to_rad(theta[p]);
      return stress[p].dot(Eigen::Vector2d(std::cos(t), std::sin(t))) / a;
    };
    r.k_continue.push_back(k(3));  // 305.26
    r.k_reverse.push_back(k(1));   // 125.26
  }
  locate_yield(r, tolerance);
  return r;
}

class ElasticRangeFcc : public ::testing::TestWithParam<std::string> {};

TEST_P(ElasticRangeFcc, MatchesTheAffineLatticeAndItsYield) {
  const DemSystem state = fcc_state();
  ElasticRangeOptions eo;
  eo.method = GetParam();
  // The ladder stops at 1.4e-2: beyond ~1.6e-2 the dynamic probes leave the affine branch
  // (with its yz bonds open the lattice is no longer stable, and the engine's round-off finds
  // a lower state), where the minimiser, with exactly balanced forces, stays on it.
  eo.amplitudes = {1e-4, 3e-3, 8e-3, 1.1e-2, 1.25e-2, 1.4e-2};
  eo.tolerance = 0.1;
  ProbeOptions po;
  po.rate = 2000.0;  // affine: the rate changes nothing at rest, so load fast
  const ElasticRange got = elastic_range(state, eo, po);
  const ElasticRange want = closed_form(eo.amplitudes, eo.tolerance);
  ASSERT_EQ(got.amplitude.size(), want.amplitude.size());
  EXPECT_NEAR(got.elastic_minor, want.elastic_minor, 1e-6 * want.elastic_minor);
  for (std::size_t i = 0; i < want.amplitude.size(); ++i) {
    const double a = want.amplitude[i];
    EXPECT_NEAR(got.minor_over_elastic[i], want.minor_over_elastic[i], 1e-6) << a;
    EXPECT_NEAR(got.k_continue[i], want.k_continue[i], 1e-6 * std::abs(want.k_reverse[i])) << a;
    EXPECT_NEAR(got.k_reverse[i], want.k_reverse[i], 1e-6 * std::abs(want.k_reverse[i])) << a;
    std::cout << "A " << a << ": minor/el " << got.minor_over_elastic[i] << ", kc/kr "
              << got.k_continue[i] / got.k_reverse[i] << ", departure " << got.departure[i]
              << " (closed form " << want.departure[i] << ")\n";
  }
  ASSERT_TRUE(want.yielded);
  ASSERT_GT(want.elastic_to, 0.0);
  EXPECT_TRUE(got.yielded);
  EXPECT_EQ(got.yield_strain, want.yield_strain);
  EXPECT_EQ(got.elastic_to, want.elastic_to);
  // The physics of the closed form: nothing departs before the first bond opens, at
  // ln(2R / r0) / sqrt(1/6) under the reverse probe (the yz bonds stretch at 0.408 |eps|).
  const double first_opening = std::log(2 * kR / kR0) * std::sqrt(6.0);
  EXPECT_GT(want.yield_strain, first_opening);
  for (std::size_t i = 0; i < want.amplitude.size(); ++i)
    if (want.amplitude[i] < first_opening) {
      EXPECT_LT(want.departure[i], 0.05) << want.amplitude[i];
    }
}

INSTANTIATE_TEST_SUITE_P(Methods, ElasticRangeFcc, ::testing::Values("dynamic", "minimisation"));

// Several states' ladders in one pool of probes (elastic_ranges, the run's stage) give each
// state the ladder elastic_range gives it alone, bit for bit, on one thread and on two, and
// each rung is the envelope minimisation_envelope gives alone (its own pool): every probe
// lands in its own state's and rung's place. Two lattices compressed differently, so that a
// probe in the wrong place would change the numbers.
TEST(ElasticRanges, SeveralStatesInOnePoolAreEachStatesOwnLadder) {
  const DemSystem a = fcc_state(), b = fcc_state(1.985e-3);
  ElasticRangeOptions eo;
  eo.amplitudes = {1e-4, 3e-3, 1.25e-2};
  for (const int threads : {1, 2}) {
    ProbeOptions po;
    po.threads = threads;
    const std::vector<ElasticRange> both = elastic_ranges({&a, &b}, eo, po);
    ASSERT_EQ(both.size(), 2u);
    const ElasticRange alone[2] = {elastic_range(a, eo, po), elastic_range(b, eo, po)};
    for (int s = 0; s < 2; ++s) {
      const ElasticRange& got = both[static_cast<std::size_t>(s)];
      const ElasticRange& want = alone[s];
      ASSERT_EQ(got.envelopes.size(), eo.amplitudes.size()) << threads;
      EXPECT_EQ(got.minor_over_elastic, want.minor_over_elastic) << threads << " " << s;
      EXPECT_EQ(got.k_continue, want.k_continue) << threads << " " << s;
      EXPECT_EQ(got.k_reverse, want.k_reverse) << threads << " " << s;
      EXPECT_EQ(got.departure, want.departure) << threads << " " << s;
      for (std::size_t k = 0; k < want.envelopes.size(); ++k) {
        const Envelope rung =
            minimisation_envelope(s == 0 ? a : b, eo.amplitudes[k], elastic_range_directions(), po);
        ASSERT_EQ(got.envelopes[k].size(), rung.size());
        for (std::size_t p = 0; p < want.envelopes[k].size(); ++p) {
          EXPECT_EQ(got.envelopes[k].d_stress[p], want.envelopes[k].d_stress[p])
              << threads << " " << s << " " << k << " " << p;
          EXPECT_EQ(got.envelopes[k].d_stress[p], rung.d_stress[p])
              << threads << " " << s << " " << k << " " << p;
          EXPECT_EQ(got.envelopes[k].d_fabric[p], rung.d_fabric[p])
              << threads << " " << s << " " << k << " " << p;
        }
      }
      EXPECT_EQ(got.seconds.size(), eo.amplitudes.size());
      // The reference is the state's linear response, kept for the run.
      const LinearResponse lr = state_linear_response(s == 0 ? a : b, po);
      ASSERT_TRUE(got.linear.ok) << got.linear.message;
      EXPECT_EQ(got.elastic_reference, "linear_response");
      EXPECT_EQ(got.linear.stiffness, lr.stiffness) << threads << " " << s;
      EXPECT_EQ(got.linear.fabric_stiffness, lr.fabric_stiffness) << threads << " " << s;
    }
    // The two lattices differ, so the test can tell them apart.
    EXPECT_NE(both[0].envelopes.back().d_stress[1], both[1].envelopes.back().d_stress[1]);
    EXPECT_NE(both[0].linear.stiffness, both[1].linear.stiffness);
  }
}

TEST(LocateYield, TheFirstRungThatDepartsAndTheRungBelow) {
  ElasticRange r;
  r.amplitude = {1e-4, 1e-3, 1e-2, 1e-1};
  r.minor_over_elastic = {1.0, 0.95, 0.7, 0.9};  // departures 0, 0.05, 0.3, 0.1
  r.k_continue = {1.0, 1.0, 1.0, 1.0};
  r.k_reverse = {1.0, 1.0, 1.0, 1.0};
  locate_yield(r, 0.2);
  EXPECT_TRUE(r.yielded);
  EXPECT_EQ(r.yield_strain, 1e-2);
  EXPECT_EQ(r.elastic_to, 1e-3);
  EXPECT_NEAR(r.departure[2], 0.3, 1e-15);
  r.k_continue = {0.5, 1.0, 1.0, 1.0};  // already departed at the first rung
  locate_yield(r, 0.2);
  EXPECT_EQ(r.yield_strain, 1e-4);
  EXPECT_EQ(r.elastic_to, 0.0);
  r.k_continue = {1.0, 1.0, 1.0, 1.0};
  r.minor_over_elastic = {1.0, 1.0, 1.05, 1.1};  // never: a lower bound, flagged
  locate_yield(r, 0.2);
  EXPECT_FALSE(r.yielded);
  EXPECT_EQ(r.yield_strain, 1e-1);
  EXPECT_EQ(r.elastic_to, 1e-1);
  r.k_reverse = {1.0, 0.0, 1.0, 1.0};  // a non-finite departure counts as departed
  locate_yield(r, 0.2);
  EXPECT_TRUE(r.yielded);
  EXPECT_EQ(r.yield_strain, 1e-3);
}

}  // namespace
}  // namespace rendulic::dem

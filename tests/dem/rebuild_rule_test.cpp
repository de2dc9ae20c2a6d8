// The rebuild rule's two largest excesses without a square root for most particles
// (neighbor_list.hpp, keep_two_largest_excess): over streams of excesses, random and placed on
// the boundary of the skip test to the last bit, e1 and e2 must come out bit for bit those of
// the plain rule, keep_two_largest(sqrt(u2) - t), which the engine used before.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <random>

#include "rendulic/dem/neighbor_list.hpp"

namespace rendulic::dem {
namespace {

std::uint64_t bits(double x) {
  std::uint64_t b;
  std::memcpy(&b, &x, sizeof b);
  return b;
}

// Feeds the same (u2, t) to both rules and compares (e1, e2) after every value.
struct BothRules {
  double e1 = -1e300, e2 = -1e300;  // the plain rule, as the engine starts each step
  double f1 = -1e300, f2 = -1e300;  // without the square root
  void feed(double u2, double t) {
    keep_two_largest(std::sqrt(u2) - t, e1, e2);
    keep_two_largest_excess(u2, t, f1, f2);
    ASSERT_EQ(bits(e1), bits(f1)) << "u2 " << u2 << " t " << t;
    ASSERT_EQ(bits(e2), bits(f2)) << "u2 " << u2 << " t " << t;
  }
};

TEST(RebuildRule, TheTwoLargestExcessesWithoutASquareRootAreThoseWithIt) {
  std::mt19937_64 rng(7);
  // Displacements of 1e-7 to 1e-3 m against half skins of about 1.5e-4 m (skin 0.3 <r>), and
  // the scale s_min of an extension, as in the engine's steps.
  std::uniform_real_distribution<double> log_u(-7.0, -3.0), h(1.5e-4, 6e-4), s(0.97, 1.0);
  for (int step = 0; step < 200; ++step) {
    BothRules r;
    const double s_min = s(rng);
    for (int i = 0; i < 2000; ++i) {
      const double u = std::pow(10.0, log_u(rng));
      r.feed(u * u, s_min * h(rng));
    }
  }
}

TEST(RebuildRule, ValuesOnTheSkipTestsBoundaryGiveTheSameBits) {
  // u2 within 64 units in the last place of (e2 + t)^2, on either side, with e2 from the size
  // of t down to 1e-14 of it and of either sign: there e2 + t rounds, and a test without its
  // margin skips values that the plain rule keeps.
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int trial = 0; trial < 20000; ++trial) {
    const double t = std::pow(10.0, -8.0 + 6.0 * unit(rng));
    const double e2 = (unit(rng) < 0.5 ? -1.0 : 1.0) * t * std::pow(10.0, -14.0 * unit(rng));
    BothRules r;
    r.e1 = r.f1 = e2 + t;
    r.e2 = r.f2 = e2;
    const double edge = e2 + t;  // sqrt(u2) = edge gives e = e2 before rounding
    if (!(edge > 0.0)) continue;
    double u2 = edge * edge;
    for (int ulp = 0; ulp < 64 && u2 > 0.0; ++ulp) u2 = std::nextafter(u2, 0.0);
    for (int ulp = 0; ulp < 128; ++ulp) {
      BothRules copy = r;
      copy.feed(u2, t);
      u2 = std::nextafter(u2, 1.0);
    }
  }
}

TEST(RebuildRule, NonFiniteDisplacementsAreKeptAsBefore) {
  BothRules r;
  r.feed(1e-8, 1e-4);
  r.feed(std::nan(""), 1e-4);
  r.feed(INFINITY, 1e-4);
  EXPECT_TRUE(std::isinf(r.f1));
}

}  // namespace
}  // namespace rendulic::dem

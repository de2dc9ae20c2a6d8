// Parallel determinism (issue 3 item 8): the same thread count gives bit-identical results,
// another thread count agrees to round-off. A system test because two threads on a shared
// machine may wait on each other for seconds.
#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>

#include "dem_helpers.hpp"

namespace rendulic::dem {
namespace {

std::vector<double> flat(const Particles& p) {
  std::vector<double> v;
  for (const auto* a : {&p.x, &p.y, &p.z, &p.vx, &p.vy, &p.vz, &p.fx, &p.fy, &p.fz})
    v.insert(v.end(), a->begin(), a->end());
  return v;
}

TEST(Determinism, DeterministicForAGivenThreadCountAndCloseAcrossCounts) {
  SystemOptions o;
  GasOptions g;
  g.n_particles = 600;  // above the serial threshold, so loops really run in parallel
  g.volume_fraction = 0.35;
  const Eigen::Vector3d D = Eigen::Vector3d::Constant(-3000.0);
  const int saved = omp_get_max_threads();
  omp_set_num_threads(2);
  DemSystem a = make_gas(o, g, 5), b = make_gas(o, g, 5);
  a.advance(100, D);
  b.advance(100, D);
  omp_set_num_threads(1);
  DemSystem c = make_gas(o, g, 5);
  c.advance(100, D);
  omp_set_num_threads(saved);
  EXPECT_EQ(flat(a.particles()), flat(b.particles()));  // same thread count: bit-identical
  // Another thread count sums the same pair forces in another order: round-off only (the gas
  // is chaotic, but 100 steps are far too few to amplify 1e-16 beyond 1e-9).
  const auto fa = flat(a.particles()), fc = flat(c.particles());
  double worst = 0;
  for (std::size_t i = 0; i < a.particles().size(); ++i)
    worst = std::max(worst, std::abs(fa[i] - fc[i]));  // positions x
  EXPECT_LT(worst, 1e-9 * a.cell().lengths[0]);
}

}  // namespace
}  // namespace rendulic::dem

// The probe tools' pair search (find_pairs, probe_geometry.hpp; docs/performance.md "FIRE's
// forces and the probe tools' pair search") against a search over all pairs with the same
// minimum image: the same pairs, in the order (i, j), with the same numbers to the bit, in
// orthorhombic cells with three or more bins per axis (each neighbouring bin one image, tested
// without roundings first), with fewer bins (neighbours without repeats) and in a sheared
// cell. And the FIRE minimiser, which searches with a skin, ends at the same positions to the
// bit whatever the skin: only the cost depends on it (probe_minimise.hpp).
#include "rendulic/dem/probe_geometry.hpp"

#include <gtest/gtest.h>

#include <random>

#include "rendulic/core/errors.hpp"
#include "rendulic/dem/probe_minimise.hpp"

namespace rendulic::dem {
namespace {

// Every pair (i < j) with r_i + r_j - |l| > -skin, l by the minimum image as find_pairs takes it.
std::vector<PairGeometry> all_pairs(const PackingData& p, double skin) {
  const Eigen::Matrix3d h_inv = p.cell.h.inverse();
  const bool ortho = p.cell.is_orthorhombic();
  std::vector<PairGeometry> out;
  for (int i = 0; i < p.size(); ++i)
    for (int j = i + 1; j < p.size(); ++j) {
      const Eigen::Vector3d dx = (p.positions.row(i) - p.positions.row(j)).transpose();
      const Eigen::Vector3d l =
          ortho ? minimum_image_orthorhombic(p.cell.h.diagonal(), h_inv.diagonal(), dx)
                : minimum_image(p.cell, h_inv, dx);
      const double r = l.norm();
      const double overlap = p.radii(i) + p.radii(j) - r;
      if (overlap > -skin) out.push_back({i, j, l, r, overlap});
    }
  return out;
}

// n random spheres (radii in [r, 3 r]) in a cube of side `side` r, some positions outside the
// cell (the minimiser does not wrap them).
PackingData random_packing(int n, double side, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const double r = 1e-3, L = side * r;
  Eigen::MatrixX3d x(n, 3);
  Eigen::VectorXd radii(n);
  for (int i = 0; i < n; ++i) {
    radii(i) = r * (1.0 + 2.0 * u(rng));
    for (int a = 0; a < 3; ++a) x(i, a) = L * (1.4 * u(rng) - 0.2);
  }
  return PackingData::orthorhombic(x, radii, Eigen::Vector3d(L, 1.1 * L, 0.9 * L));
}

void expect_same_pairs(const PackingData& p, double skin) {
  const std::vector<PairGeometry> want = all_pairs(p, skin), got = find_pairs(p, skin);
  ASSERT_FALSE(want.empty());
  ASSERT_EQ(got.size(), want.size());
  for (std::size_t k = 0; k < got.size(); ++k) {
    ASSERT_EQ(got[k].i, want[k].i) << k;
    ASSERT_EQ(got[k].j, want[k].j) << k;
    ASSERT_EQ(got[k].l, want[k].l) << k;  // bitwise: the same minimum image
    ASSERT_EQ(got[k].distance, want[k].distance) << k;
    ASSERT_EQ(got[k].overlap, want[k].overlap) << k;
  }
  std::vector<PairGeometry> unordered;
  find_pairs_unordered(p, skin, unordered);
  EXPECT_EQ(unordered.size(), want.size());
}

TEST(FindPairs, EqualsTheSearchOverAllPairsWithManyBinsPerAxis) {
  for (double skin : {0.0, 0.5e-3, 1.5e-3}) expect_same_pairs(random_packing(600, 30.0, 1), skin);
}

TEST(FindPairs, EqualsTheSearchOverAllPairsWithFewBinsPerAxis) {
  // 16 r is below three contact ranges (2 r_max + skin = 6-7 r): one or two bins per axis.
  for (double skin : {0.0, 0.5e-3}) expect_same_pairs(random_packing(60, 16.0, 2), skin);
}

TEST(FindPairs, EqualsTheSearchOverAllPairsInADiluteCell) {
  // 40 spheres in a cube of 1e5 r: 1e12 bins of one contact range, which overflowed the bin
  // count, before their number was bounded (cell_list_bins). Half of them touch a partner, one
  // pair across the cell's face.
  PackingData p = random_packing(40, 1e5, 4);
  const double L = p.cell.h(0, 0);
  for (int i = 0; i + 1 < p.size(); i += 2) {
    p.positions.row(i + 1) = p.positions.row(i);
    p.positions(i + 1, 0) += 0.9 * (p.radii(i) + p.radii(i + 1));
  }
  p.positions(0, 0) = L - 0.2 * p.radii(0);
  p.positions(1, 0) = 0.5 * p.radii(1);
  for (double skin : {0.0, 0.5e-3}) expect_same_pairs(p, skin);
  EXPECT_EQ(find_pairs(p, 0.0).size(), 20u);
}

// A finite position beyond the range of the cell's coordinates (-1e308 m, a damaged results
// file: its fractional coordinate is -inf) is refused naming the particle; its bin was out of
// the table and the search crashed. Far but within range, a position is wrapped as any other.
TEST(FindPairs, APositionTooFarToWrapIsRefusedNamingTheParticle) {
  PackingData p = random_packing(30, 20.0, 5);
  p.positions(7, 1) = -1e308;
  try {
    find_pairs(p, 0.0);
    ADD_FAILURE() << "searched a packing with a particle at -1e308 m";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("packing: particle 7 at "), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("too far from the cell to be wrapped"), std::string::npos)
        << e.what();
  }
  p.positions(7, 1) = -1e300;
  EXPECT_NO_THROW(find_pairs(p, 0.0));
}

TEST(FindPairs, EqualsTheSearchOverAllPairsInAShearedCell) {
  PackingData p = random_packing(600, 30.0, 3);
  Eigen::Matrix3d F = Eigen::Matrix3d::Identity();
  F(0, 1) = 0.08;
  F(1, 2) = -0.05;
  p.deform(F);
  ASSERT_FALSE(p.cell.is_orthorhombic());
  for (double skin : {0.0, 0.5e-3}) expect_same_pairs(p, skin);
}

TEST(FindPairs, TheSkinOfTheMinimiserChangesItsCostNotItsResult) {
  GeneratedPackingOptions g;
  g.n = 300;
  g.volume_fraction = 0.72;
  g.seed = 5;
  g.minimise.max_iterations = 300;  // far from the minimum: particles move and lists rebuild
  const PackingData start = generate_packing(g, nullptr);
  MinimiseOptions o;
  o.force_tolerance = 1e-10;
  PackingData a = start, b = start;
  o.skin = 0.1;
  const MinimiseSummary sa = minimise_energy(a, o);
  o.skin = 0.8;
  const MinimiseSummary sb = minimise_energy(b, o);
  EXPECT_TRUE(sa.converged);
  EXPECT_GT(sa.pair_rebuilds, sb.pair_rebuilds);
  EXPECT_EQ(sa.iterations, sb.iterations);
  EXPECT_TRUE(a.positions == b.positions);  // bitwise
  EXPECT_EQ(sa.elastic_energy, sb.elastic_energy);
}

}  // namespace
}  // namespace rendulic::dem

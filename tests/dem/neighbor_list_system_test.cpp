// The Verlet list with per-particle skins (neighbor_list.hpp): its rebuild rule
// must be exact, i.e. the list-based contact set equals a brute-force all-pairs search after
// every single step, in a hot, dense packing that is being deformed (the case where a too-loose
// rule would miss contacts), while the skins actually differ between particles. Also the bounds of
// the skin choice, on which the bin size (and so the exactness) relies.
#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <map>
#include <utility>

#include "rendulic/dem/neighbor_list.hpp"
#include "rendulic/dem/protocols.hpp"

namespace rendulic::dem {
namespace {

using PairList = std::vector<std::pair<int, int>>;

PairList brute_force_contacts(const DemSystem& s) {
  const Particles& p = s.particles();
  const Eigen::Vector3d L = s.cell().lengths();
  PairList out;
  for (std::size_t i = 0; i < p.size(); ++i)
    for (std::size_t j = i + 1; j < p.size(); ++j) {
      Eigen::Vector3d l = p.position(i) - p.position(j);
      for (int a = 0; a < 3; ++a) l[a] -= L[a] * std::round(l[a] / L[a]);
      if (l.norm() < p.radius[i] + p.radius[j])
        out.emplace_back(static_cast<int>(i), static_cast<int>(j));
    }
  return out;  // sorted by construction
}

PairList list_contacts(const DemSystem& s) {
  PairList out;
  for (const Contact& c : s.contacts()) out.emplace_back(c.i, c.j);
  std::sort(out.begin(), out.end());
  return out;
}

TEST(NeighborList, NeverMissesAContactInAHotDeformingPacking) {
  omp_set_num_threads(1);  // about the list, not the threads; small N is faster serial
  SystemOptions o;
  o.material.gamma_b = 0.0;  // no background damping: the packing stays hot
  GasOptions g;
  g.n_particles = 300;
  g.velocity = 5.0;
  DemSystem s = make_gas(o, g, 7);
  CompressOptions c;
  c.target_nu = 0.72;  // jammed: every particle in a cage, rattlers free
  c.rate_max = c.rate_min = 3000.0;
  compress_isotropic(s, c);
  // Heat it: random kicks of tens of m/s, the scale of the fastest rattlers at nu = 0.82.
  Rng rng(3);
  for (std::size_t i = 0; i < s.particles().size(); ++i) {
    s.mutable_particles().vx[i] += 20.0 * rng.normal();
    s.mutable_particles().vy[i] += 20.0 * rng.normal();
    s.mutable_particles().vz[i] += 20.0 * rng.normal();
  }
  s.refresh_forces();
  const double h0 = 0.5 * o.skin * o.material.r_mean;
  const std::int64_t builds0 = s.list_builds();
  bool skins_differ = false;
  std::size_t checked = 0;
  for (int k = 0; k < 1500; ++k) {
    // Alternate extension and compression so that the cell-shrink term of the rule is used.
    const double rate = (k / 300) % 2 == 0 ? 2000.0 : -2000.0;
    s.step(Eigen::Vector3d(rate, -0.5 * rate, -0.5 * rate));
    const auto brute = brute_force_contacts(s);
    ASSERT_EQ(list_contacts(s), brute) << "after " << s.steps() << " steps";
    checked += brute.size();
    if (k % 50 == 0) {
      const std::vector<double> h = s.save().ref_half_skin;
      skins_differ |= *std::max_element(h.begin(), h.end()) > 1.5 * h0;
    }
  }
  EXPECT_GT(checked, 1500u * 300u);          // a dense packing, not a gas
  EXPECT_GT(s.list_builds() - builds0, 10);  // the rule was exercised many times
  EXPECT_TRUE(skins_differ);                 // per-particle skins were in play
}

// The binned search (a stencil row's bins as one run of candidates, split where it wraps
// around the cell, tested in lanes where the build has them) against every pair and every
// image: each pair within reach, r_i + h_i + r_j + h_j, listed once and with its image; none
// beyond it; rows ascending. Pairs within 1e-9 of the reach are left to rounding.
TEST(NeighborList, TheBinnedSearchListsEveryPairWithinReachOnce) {
  omp_set_num_threads(1);
  GasOptions g;
  g.n_particles = 400;
  DemSystem s = make_gas(SystemOptions{}, g, 5);
  CompressOptions c;
  c.target_nu = 0.7;
  c.rate_max = c.rate_min = 3000.0;
  compress_isotropic(s, c);
  const Particles& p = s.particles();
  const Eigen::Vector3d L = s.cell().lengths();
  const std::size_t n = p.size();
  const double skin = 0.3 * SystemOptions{}.material.r_mean;
  Rng rng(2);
  std::vector<double> h(n);
  const double r_max = *std::max_element(p.radius.begin(), p.radius.end());
  for (std::size_t i = 0; i < n; ++i)  // the bounds of choose_half_skins
    h[i] = std::min(0.5 * skin * rng.uniform(1.0, kMaxSkinRatio), r_max + 0.5 * skin - p.radius[i]);
  for (int threads : {1, 2}) {
    NeighborList list;
    list.build(p, L, skin, h, threads);
    ASSERT_GE(L.minCoeff(), 3 * (2 * r_max + skin));  // binned, not the all-pairs search
    // (i, j) with i < j -> the image of j seen from i, l = x_i - x_j + s L.
    std::map<std::pair<int, int>, Eigen::Vector3d> listed;
    for (std::size_t r = 0; r < n; ++r)
      for (std::int64_t e = list.offset[r]; e < list.offset[r + 1]; ++e) {
        const int row = static_cast<int>(r), j = list.index[e];
        if (e > list.offset[r]) {
          EXPECT_LT(list.index[e - 1], j) << "row " << r;
        }
        const Eigen::Vector3d s_row = NeighborList::shift(list.shift_code[e]);
        const bool fresh = row < j
                               ? listed.emplace(std::pair{row, j}, s_row).second
                               : listed.emplace(std::pair{j, row}, Eigen::Vector3d(-s_row)).second;
        EXPECT_TRUE(fresh) << "listed twice: " << r << " " << j;
      }
    std::size_t within = 0;
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t j = i + 1; j < n; ++j)
        for (std::uint8_t code = 0; code < 27; ++code) {
          const Eigen::Vector3d sh = NeighborList::shift(code);
          const Eigen::Vector3d l = p.position(i) - p.position(j) + sh.cwiseProduct(L);
          const double reach = p.radius[i] + h[i] + p.radius[j] + h[j], d = l.norm();
          const auto it = listed.find({static_cast<int>(i), static_cast<int>(j)});
          const bool as_listed = it != listed.end() && it->second == sh;
          if (d < reach * (1 - 1e-9)) {
            ++within;
            EXPECT_TRUE(as_listed) << "missing: " << i << " " << j << " image " << int(code);
          } else if (d > reach * (1 + 1e-9)) {
            EXPECT_FALSE(as_listed) << "beyond reach: " << i << " " << j;
          }
        }
    EXPECT_EQ(within, listed.size());  // nothing listed beyond reach either
    EXPECT_GT(within, 4 * n);
  }
}

TEST(NeighborList, HalfSkinsStayWithinTheirBounds) {
  Rng rng(11);
  const std::size_t n = 500;
  const double skin = 3e-4, h0 = 0.5 * skin;
  std::vector<double> r(n), u(n);
  for (std::size_t i = 0; i < n; ++i) {
    r[i] = rng.uniform(5e-4, 1.5e-3);
    u[i] = 1e-6 * std::exp(4 * rng.normal());  // heavy tail, like rattlers
  }
  const double r_max = *std::max_element(r.begin(), r.end());
  const std::vector<double> h = choose_half_skins(u, r, skin);
  ASSERT_EQ(h.size(), n);
  std::size_t wider = 0;
  for (std::size_t i = 0; i < n; ++i) {
    EXPECT_GE(h[i], h0);
    EXPECT_LE(h[i], kMaxSkinRatio * h0 * (1 + 1e-12));
    EXPECT_LE(r[i] + h[i], (r_max + h0) * (1 + 1e-12));  // bins of the common skin suffice
    wider += h[i] > h0;
  }
  // About the 5 % above the 95th percentile get more; the rest keep the common skin.
  EXPECT_GT(wider, n / 50);
  EXPECT_LT(wider, n / 10);
  // No history (first build) or a system at rest: the common skin everywhere.
  for (double x : choose_half_skins({}, r, skin)) EXPECT_EQ(x, h0);
  for (double x : choose_half_skins(std::vector<double>(n, 0.0), r, skin)) EXPECT_EQ(x, h0);
}

}  // namespace
}  // namespace rendulic::dem

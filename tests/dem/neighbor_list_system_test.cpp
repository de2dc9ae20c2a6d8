// The Verlet list with per-particle skins (neighbor_list.hpp): its rebuild rule
// must be exact, i.e. the list-based contact set equals a brute-force all-pairs search after
// every single step, in a hot, dense packing that is being deformed (the case where a too-loose
// rule would miss contacts), while the skins actually differ between particles. Also the bounds of
// the skin choice, on which the bin size (and so the exactness) relies.
#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <utility>

#include "rendulic/core/errors.hpp"
#include "rendulic/dem/cell.hpp"
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
// Every pair (i < j) and periodic image within r_i + h_i + r_j + h_j is listed once, with that
// image, and nothing beyond reach: the list against a search over all pairs and 27 images.
// Returns the number of pairs within reach.
std::size_t expect_every_pair_within_reach_listed_once(const Particles& p, const Eigen::Vector3d& L,
                                                       const std::vector<double>& h,
                                                       const NeighborList& list) {
  const std::size_t n = p.size();
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
  return within;
}

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
    EXPECT_GT(expect_every_pair_within_reach_listed_once(p, L, h, list), 4 * n);
  }
}

// The engine's list and the probe tools' pair search refused a cell narrower than twice the
// interaction range in two wordings ("cell width ... the minimum image would be ambiguous");
// one now, naming the axis. A NaN width (a damaged cell) is refused too.
TEST(CellListBins, ACellNarrowerThanTwiceTheRangeIsRefusedNamingItsAxis) {
  EXPECT_NO_THROW(require_minimum_image(Eigen::Vector3d(1.0, 0.61, 1.0), 0.3));
  try {
    require_minimum_image(Eigen::Vector3d(1.0, 0.6, 1.0), 0.3);
    ADD_FAILURE() << "a width of exactly twice the range was accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()),
              "periodic cell too small: width 0.6 m on axis 1 must exceed twice the interaction "
              "range 0.3 m, or the minimum image is ambiguous (use more particles or a smaller "
              "skin)");
  }
  EXPECT_THROW(require_minimum_image(
                   Eigen::Vector3d(1.0, 1.0, std::numeric_limits<double>::quiet_NaN()), 0.3),
               InputError);
  // The engine's list asks the same question.
  Particles p;
  p.resize(2);
  p.radius = {0.1, 0.1};
  p.x = {0.1, 0.5};
  p.y = {0.1, 0.1};
  p.z = {0.1, 0.1};
  NeighborList list;
  EXPECT_THROW(list.build(p, Eigen::Vector3d(1.0, 0.6, 1.0), 0.1), InputError);
}

TEST(CellListBins, AsManyAsFitInADenseCellBoundedInADiluteOne) {
  const auto product = [](const std::array<int, 3>& b) { return double(b[0]) * b[1] * b[2]; };
  // Dense: every bin as narrow as allowed, and no fewer than one.
  EXPECT_EQ(cell_list_bins(Eigen::Vector3d(10.5, 20.2, 3.1), 1.0, 1000),
            (std::array<int, 3>{10, 20, 3}));
  EXPECT_EQ(cell_list_bins(Eigen::Vector3d(0.5, 2.0, 1.0), 1.0, 10), (std::array<int, 3>{1, 2, 1}));
  // Dilute: at most max(2^16, 64 n) bins, alike along equal axes, never narrower than asked.
  const Eigen::Vector3d wide = Eigen::Vector3d::Constant(1e6);
  const std::array<int, 3> few = cell_list_bins(wide, 1.0, 10);
  EXPECT_LE(product(few), 65536.0);
  EXPECT_EQ(few, (std::array<int, 3>{40, 40, 40}));
  const std::array<int, 3> many = cell_list_bins(wide, 1.0, 1000000);
  EXPECT_LE(product(many), kMaxBinsPerParticle * 1e6);
  EXPECT_GT(product(many), 0.9 * kMaxBinsPerParticle * 1e6);
  // A slab: its thin axis keeps its one bin and the others share the bound.
  const std::array<int, 3> slab = cell_list_bins(Eigen::Vector3d(1e9, 1e9, 1.5), 1.0, 10);
  EXPECT_EQ(slab[2], 1);
  EXPECT_LE(product(slab), 65536.0);
  EXPECT_GE(slab[0], 200);
  // Widths no int can count: still a bounded, positive number of bins.
  for (const Eigen::Vector3d& w :
       {Eigen::Vector3d(1e300, 1e300, 1e300), Eigen::Vector3d(1e300, 1.0, 1e300),
        Eigen::Vector3d(std::numeric_limits<double>::infinity(), 5.0,
                        std::numeric_limits<double>::quiet_NaN())}) {
    const std::array<int, 3> b = cell_list_bins(w, 1e-3, 4);
    for (int a = 0; a < 3; ++a) {
      EXPECT_GE(b[a], 1);
      if (std::isfinite(w[a])) {
        EXPECT_GE(w[a] / b[a], 1e-3);
      }
    }
    EXPECT_LE(product(b), 65536.0);
  }
}

TEST(NeighborList, ADiluteCellIsListedCompletelyWithBoundedBins) {
  // 40 particles 1 mm in a box of 10 m: 2.4e12 bins of one contact range each, which overflowed
  // the bin index and asked for terabytes before the bound. Pairs in reach, some of them across
  // the box's faces, among particles spread at random.
  const double r = 1e-3, L0 = 10.0, skin = 3e-4;
  const Eigen::Vector3d L = Eigen::Vector3d::Constant(L0);
  Rng rng(4);
  Particles p;
  p.resize(40);
  for (std::size_t i = 0; i < p.size(); i += 2) {
    const Eigen::Vector3d x(rng.uniform(0, L0), rng.uniform(0, L0), rng.uniform(0, L0));
    Eigen::Vector3d y = x + Eigen::Vector3d(rng.uniform(1.5, 2.1) * r, 0.0, 0.0);
    p.x[i] = x[0];
    if (i % 4 == 0) {  // across the face x = L
      p.x[i] = L0 - rng.uniform(0.0, 1.5 * r);
      y[0] = rng.uniform(0.0, 0.5 * r);
    }
    p.y[i] = x[1], p.z[i] = x[2];
    p.x[i + 1] = y[0], p.y[i + 1] = x[1], p.z[i + 1] = x[2];
    p.radius[i] = p.radius[i + 1] = r;
    p.inv_mass[i] = p.inv_mass[i + 1] = 1.0;
  }
  const std::vector<double> h(p.size(), 0.5 * skin);
  NeighborList list;
  list.build(p, L, skin, h, 1);
  EXPECT_EQ(expect_every_pair_within_reach_listed_once(p, L, h, list), p.size() / 2);
}

TEST(NeighborList, AGasFarTooDiluteForOneBinPerRangeIsMadeAndStepped) {
  // The sparsest gas, preparation.nu_gas = 1e-6: bins of 2 r_max would number ~10^7; the
  // random insertion's bins and the list's are both bounded (before, at 1e-9, 420 GB asked for
  // and std::bad_alloc).
  GasOptions g;
  g.n_particles = 60;
  g.volume_fraction = kGasVolumeFractionMin;
  DemSystem s = make_gas(SystemOptions{}, g, 3);
  ASSERT_EQ(s.particles().size(), 60u);
  for (int k = 0; k < 10; ++k) s.step(Eigen::Vector3d::Constant(-100.0));
  EXPECT_EQ(s.measure().contacts, 0);
  EXPECT_NEAR(s.volume_fraction(), 1e-6, 1e-7);
  // Sparser is refused: compressing 1e-300 to nu0 had not ended after 30 s at N = 250.
  g.volume_fraction = 1e-300;
  std::string why;
  EXPECT_FALSE(g.IsValid(&why));
  EXPECT_EQ(why, "gas volume fraction must be in [1e-06, 0.4]");
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

// Cell-list construction of the half Verlet list with per-particle skins, its rebuild rule and
// the choice of the skins (see neighbor_list.hpp).
#include "rendulic/dem/neighbor_list.hpp"

#include <omp.h>
#if defined(__AVX512F__)
#include <immintrin.h>
#endif

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <numeric>
#include <sstream>
#include <stdexcept>

#include "rendulic/core/errors.hpp"
#include "rendulic/dem/cell.hpp"

namespace rendulic::dem {
namespace {

std::uint8_t encode(int sx, int sy, int sz) {
  return static_cast<std::uint8_t>((sx + 1) + 3 * (sy + 1) + 9 * (sz + 1));
}

// Without bins (fewer than three on some axis): calls visit(j, code, ox, oy, oz) for every
// j > i, seen through its image nearest to i, in index order; (ox, oy, oz) = s L is the image
// offset of the code. The binned search (the half stencil) is NeighborList::build's own.
template <class Visit>
void for_later_images(std::size_t i, const Particles& p, const Eigen::Vector3d& L, Visit&& visit) {
  for (std::size_t j = i + 1; j < p.size(); ++j) {
    const int sx = -static_cast<int>(std::lround((p.x[i] - p.x[j]) / L[0]));
    const int sy = -static_cast<int>(std::lround((p.y[i] - p.y[j]) / L[1]));
    const int sz = -static_cast<int>(std::lround((p.z[i] - p.z[j]) / L[2]));
    visit(static_cast<std::int32_t>(j), encode(sx, sy, sz), sx * L[0], sy * L[1], sz * L[2]);
  }
}

}  // namespace

void NeighborList::build(const Particles& p, const Eigen::Vector3d& L, double skin) {
  build(p, L, skin, std::vector<double>(p.size(), 0.5 * skin));
}

bool NeighborList::half_skins_fit(const std::vector<double>& radius, double skin,
                                  const std::vector<double>& half_skins) {
  if (half_skins.size() != radius.size()) return false;
  const double r_max = radius.empty() ? 0.0 : *std::max_element(radius.begin(), radius.end());
  for (std::size_t i = 0; i < radius.size(); ++i)
    if (!(half_skins[i] >= 0.5 * skin * (1 - 1e-12) &&
          radius[i] + half_skins[i] <= (r_max + 0.5 * skin) * (1 + 1e-12)))
      return false;
  return true;
}

void NeighborList::build(const Particles& p, const Eigen::Vector3d& L, double skin,
                         std::vector<double> half_skins, int threads) {
  const std::size_t n = p.size();
  r_max_ = n ? *std::max_element(p.radius.begin(), p.radius.end()) : 0.0;
  skin_ = skin;
  if (half_skins.size() != n)
    throw std::invalid_argument("NeighborList::build: one half skin per particle");
  if (!half_skins_fit(p.radius, skin, half_skins))
    throw std::invalid_argument("NeighborList::build: half skin out of its bounds");
  half_skin_ = std::move(half_skins);
  const double cutoff = 2.0 * r_max_ + skin;
  require_minimum_image(L, cutoff);
  ref_x_ = p.x;
  ref_y_ = p.y;
  ref_z_ = p.z;
  ref_lengths_ = L;

  const std::array<int, 3> nb = cell_list_bins(L, cutoff, n);
  const bool brute = *std::min_element(nb.begin(), nb.end()) < 3;
  std::vector<int> bin_of(n, 0);
  std::vector<std::int64_t> bin_start;
  std::vector<std::int32_t> bin_members;
  if (!brute) {
    const int nbins = nb[0] * nb[1] * nb[2];
    bin_start.assign(nbins + 1, 0);
    for (std::size_t i = 0; i < n; ++i) {
      const double q[3] = {p.x[i] / L[0], p.y[i] / L[1], p.z[i] / L[2]};
      int c[3];
      for (int a = 0; a < 3; ++a) c[a] = std::clamp(static_cast<int>(q[a] * nb[a]), 0, nb[a] - 1);
      bin_of[i] = c[0] + nb[0] * (c[1] + nb[1] * c[2]);
      ++bin_start[bin_of[i] + 1];
    }
    std::partial_sum(bin_start.begin(), bin_start.end(), bin_start.begin());
    bin_members.resize(n);
    std::vector<std::int64_t> fill(bin_start.begin(), bin_start.end() - 1);
    for (std::size_t i = 0; i < n; ++i)
      bin_members[fill[bin_of[i]]++] = static_cast<std::int32_t>(i);
  }

  if (threads <= 0) threads = omp_get_max_threads();
  if (n <= 256) threads = 1;
  // Copies of (x, y, z, r + h) in bin order: the candidates of a bin are contiguous, read in
  // sequence, and tested without a branch (about one in fourteen is a hit).
  std::vector<double> bx, by, bz, bc;
  std::size_t most_candidates = n;
  if (!brute) {
    bx.resize(n), by.resize(n), bz.resize(n), bc.resize(n);
#pragma omp parallel for schedule(static) num_threads(threads) if (threads > 1)
    for (std::size_t k = 0; k < n; ++k) {
      const std::size_t i = static_cast<std::size_t>(bin_members[k]);
      bx[k] = p.x[i], by[k] = p.y[i], bz[k] = p.z[i], bc[k] = p.radius[i] + half_skin_[i];
    }
    std::int64_t fullest = 0;
    for (std::size_t c = 0; c + 1 < bin_start.size(); ++c)
      fullest = std::max(fullest, bin_start[c + 1] - bin_start[c]);
    most_candidates = static_cast<std::size_t>(14 * fullest);
  }
  std::vector<std::int64_t> sorted_pos;
  if (!brute) {
    sorted_pos.resize(n);
    for (std::size_t k = 0; k < n; ++k) sorted_pos[static_cast<std::size_t>(bin_members[k])] = k;
  }

  // One pass: each thread appends its (contiguous, static) range of particles to its own
  // arrays, which are then concatenated in thread order.
  // A cache line per thread: the vectors grow at every row, and headers of two threads in one
  // line moved that line between the cores at every row (as `first` below).
  struct alignas(64) Rows {
    std::vector<std::int32_t> J;
    std::vector<std::uint8_t> C;
  };
  std::vector<Rows> rows(threads);
  std::vector<std::size_t> first(threads, n);
  std::vector<std::int64_t> count(n + 1, 0);
#pragma omp parallel num_threads(threads) if (threads > 1)
  {
    const int t = omp_get_thread_num();
    auto& J = rows[t].J;
    auto& C = rows[t].C;
    J.reserve(8 * n / threads + 16);
    C.reserve(8 * n / threads + 16);
    // Eight places of slack: the lanes below write whole vectors past the last hit.
    std::vector<std::int64_t> hit_k(most_candidates + 8);
    std::vector<std::uint8_t> hit_code(most_candidates + 8);
    // The candidates k0 <= k < k1 of one bin seen from (ox, oy, oz) with reach ci: their bin
    // positions appended to hit_k (in order) where |x - x_k|^2 < (ci + c_k)^2, code beside.
    // In lanes the square sum is fused as GCC contracts the scalar form where the hardware has
    // FMA, fma(ez, ez, fma(ey, ey, ex ex)): the lanes keep exactly the pairs the scalar loop
    // kept (quick.toml's DEM stages give the same bits).
    const auto test_candidates = [&](std::int64_t k0, std::int64_t k1, double ox, double oy,
                                     double oz, double ci, std::uint8_t code, std::size_t hits) {
#if defined(__AVX512F__) && defined(__FMA__)
      // Eight candidates at a time, the hits compressed in a register and stored whole (a
      // compressing store to memory is slow on some cores): the scalar loop's dozen
      // instructions per candidate dominated the list build (docs/performance.md).
      const __m512d vx = _mm512_set1_pd(ox), vy = _mm512_set1_pd(oy), vz = _mm512_set1_pd(oz),
                    vc = _mm512_set1_pd(ci);
      const __m512i step = _mm512_set1_epi64(8);
      __m512i kv =
          _mm512_add_epi64(_mm512_set1_epi64(k0), _mm512_setr_epi64(0, 1, 2, 3, 4, 5, 6, 7));
      for (std::int64_t k = k0; k < k1; k += 8) {
        const __mmask8 in = k1 - k >= 8 ? __mmask8(0xff) : __mmask8((1u << (k1 - k)) - 1u);
        const __m512d ex = _mm512_sub_pd(vx, _mm512_maskz_loadu_pd(in, bx.data() + k));
        const __m512d ey = _mm512_sub_pd(vy, _mm512_maskz_loadu_pd(in, by.data() + k));
        const __m512d ez = _mm512_sub_pd(vz, _mm512_maskz_loadu_pd(in, bz.data() + k));
        const __m512d rc = _mm512_add_pd(vc, _mm512_maskz_loadu_pd(in, bc.data() + k));
        const __m512d r2 = _mm512_fmadd_pd(ez, ez, _mm512_fmadd_pd(ey, ey, _mm512_mul_pd(ex, ex)));
        const __mmask8 hit = _mm512_mask_cmp_pd_mask(in, r2, _mm512_mul_pd(rc, rc), _CMP_LT_OQ);
        _mm512_storeu_si512(hit_k.data() + hits, _mm512_maskz_compress_epi64(hit, kv));
        std::memset(hit_code.data() + hits, code, 8);
        hits += static_cast<std::size_t>(__builtin_popcount(hit));
        kv = _mm512_add_epi64(kv, step);
      }
#else
      for (std::int64_t k = k0; k < k1; ++k) {
        const double ex = ox - bx[k], ey = oy - by[k], ez = oz - bz[k], rc = ci + bc[k];
        hit_k[hits] = k;
        hit_code[hits] = code;
        hits += ex * ex + ey * ey + ez * ez < rc * rc;
      }
#endif
      return hits;
    };
    // The thread's first row in a register: stored to first[t] at every row, the team's entries
    // of `first` share a cache line that went back and forth between the cores, which made
    // each thread's rows ~1.6x slower on two threads than on one (docs/performance.md).
    std::size_t mine = n;
#pragma omp for schedule(static) nowait
    for (std::size_t i = 0; i < n; ++i) {
      mine = std::min(mine, i);
      const std::size_t s = J.size();
      const double xi = p.x[i], yi = p.y[i], zi = p.z[i], ci = p.radius[i] + half_skin_[i];
      if (brute) {
        for_later_images(
            i, p, L, [&](std::int32_t j, std::uint8_t code, double ox, double oy, double oz) {
              const std::size_t u = static_cast<std::size_t>(j);
              const double dx = xi - p.x[u] + ox, dy = yi - p.y[u] + oy, dz = zi - p.z[u] + oz,
                           rc = ci + p.radius[u] + half_skin_[u];
              if (dx * dx + dy * dy + dz * dz < rc * rc) {
                J.push_back(j);
                C.push_back(code);
              }
            });
      } else {
        const int b = bin_of[i];
        const int ibx = b % nb[0], iby = (b / nb[0]) % nb[1], ibz = b / (nb[0] * nb[1]);
        std::size_t hits = 0;
        // Half stencil: the own bin (partners after i in bin order, i.e. of higher index) and
        // the 13 "forward" bins, so that each pair is met once (nb >= 3 on every axis makes the
        // 27 bins distinct). Bins adjacent along x are adjacent in bin order: a stencil row
        // (dy, dz) is one run of candidates, two where it wraps around the cell, which tests
        // them in lanes without a loop per bin. The list's rows come out sorted below, so
        // the order of the runs does not matter.
        for (int dz = 0; dz <= 1; ++dz)
          for (int dy = -1; dy <= 1; ++dy) {
            if (dz == 0 && dy < 0) continue;
            int cy = iby + dy, cz = ibz + dz;
            // A partner in a wrapped bin is seen through its image: l = x_i - x_j + s L.
            int sy = 0, sz = 0;
            if (cy < 0) cy += nb[1], sy = 1;
            if (cy >= nb[1]) cy -= nb[1], sy = -1;
            if (cz >= nb[2]) cz -= nb[2], sz = -1;
            const auto shift_x = [&](int dx) {
              return ibx + dx < 0 ? 1 : ibx + dx >= nb[0] ? -1 : 0;
            };
            const bool own_row = dz == 0 && dy == 0;
            for (int dx = own_row ? 0 : -1; dx <= 1;) {
              const int sx = shift_x(dx);
              int last = dx;
              while (last < 1 && shift_x(last + 1) == sx) ++last;
              const int c = ibx + dx + sx * nb[0] + nb[0] * (cy + nb[1] * cz);
              const std::uint8_t code = encode(sx, sy, sz);
              const double ox = xi + sx * L[0], oy = yi + sy * L[1], oz = zi + sz * L[2];
              const std::int64_t k0 = own_row && dx == 0 ? sorted_pos[i] + 1 : bin_start[c];
              hits = test_candidates(k0, bin_start[c + last - dx + 1], ox, oy, oz, ci, code, hits);
              dx = last + 1;
            }
          }
#if defined(__AVX512F__)
        if (hits <= 16) {
          // Each hit straight to its place in the ascending row, by its rank among the row's
          // (distinct) partners counted in one comparison of sixteen lanes: the insertion
          // sort below then finds the row in order. Sorting by moves cost a quarter of the
          // build, on branches as unpredictable as the partners' order (docs/performance.md).
          alignas(64) std::int32_t js[16];
          for (std::size_t h = 0; h < hits; ++h) js[h] = bin_members[hit_k[h]];
          const __m512i row =
              _mm512_mask_loadu_epi32(_mm512_set1_epi32(std::numeric_limits<std::int32_t>::max()),
                                      static_cast<__mmask16>((1u << hits) - 1u), js);
          J.resize(s + hits);
          C.resize(s + hits);
          for (std::size_t h = 0; h < hits; ++h) {
            const std::size_t rank = static_cast<std::size_t>(
                __builtin_popcount(_mm512_cmplt_epi32_mask(row, _mm512_set1_epi32(js[h]))));
            J[s + rank] = js[h];
            C[s + rank] = hit_code[h];
          }
        } else
#endif
        {
          for (std::size_t h = 0; h < hits; ++h) {
            J.push_back(bin_members[hit_k[h]]);
            C.push_back(hit_code[h]);
          }
          // Ascending partner index (friendlier memory access in the force loop); the brute
          // search meets the partners in that order already.
          for (std::size_t a = s + 1; a < J.size(); ++a)
            for (std::size_t c = a; c > s && J[c - 1] > J[c]; --c) {
              std::swap(J[c - 1], J[c]);
              std::swap(C[c - 1], C[c]);
            }
        }
      }
      count[i + 1] = static_cast<std::int64_t>(J.size() - s);
    }
    first[t] = mine;
  }
  offset.assign(n + 1, 0);
  std::partial_sum(count.begin(), count.end(), offset.begin());
  index.resize(offset[n]);
  shift_code.resize(offset[n]);
  for (int t = 0; t < threads; ++t) {
    if (rows[t].J.empty()) continue;
    std::copy(rows[t].J.begin(), rows[t].J.end(), index.begin() + offset[first[t]]);
    std::copy(rows[t].C.begin(), rows[t].C.end(), shift_code.begin() + offset[first[t]]);
  }
  ++builds_;
}

bool NeighborList::must_rebuild(double e1, double e2, const Eigen::Vector3d& L) const {
  const double shrink = std::max(0.0, 1.0 - s_min(L)) * 2.0 * r_max_;
  return e1 + e2 + shrink >= 0.0;
}

std::vector<double> choose_half_skins(const std::vector<double>& u,
                                      const std::vector<double>& radius, double skin) {
  const std::size_t n = radius.size();
  const double h0 = 0.5 * skin;
  std::vector<double> h(n, h0);
  if (u.size() != n || n < 20) return h;
  std::vector<double> sorted = u;
  const auto q = sorted.begin() + static_cast<std::ptrdiff_t>(0.95 * static_cast<double>(n));
  std::nth_element(sorted.begin(), q, sorted.end());
  const double u_ref = *q;
  if (!(u_ref > 0) || !std::isfinite(u_ref)) return h;
  const double r_max = *std::max_element(radius.begin(), radius.end());
  for (std::size_t i = 0; i < n; ++i) {
    const double cap = std::max(h0, std::min(kMaxSkinRatio * h0, r_max + h0 - radius[i]));
    h[i] = std::clamp(h0 * u[i] / u_ref, h0, cap);
  }
  return h;
}

}  // namespace rendulic::dem

// The frictionless pair loop of the DEM engine (dem_system.hpp; docs/physics.md section 1,
// docs/performance.md "Engine speed"): a per-particle gather over the half neighbour list
// from packed records (position + radius; velocity + force accumulator), the periodic images
// through the blocks' foreign slots. Two forms that give the same bits (branchy, and compact:
// the touching entries gathered first), the step choosing by timing; the branchy one meets
// each row's contacts first (partner_first_, docs/performance.md "Contacts first in each
// row"). Measured alternatives that lost are listed in docs/performance.md.
#if defined(__AVX__)
#include <immintrin.h>
#endif

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <vector>

#include "contacts_first.hpp"
#include "rendulic/dem/dem_system.hpp"
#include "vec4.hpp"

namespace rendulic::dem {
using namespace vec4;

void DemSystem::reset_contacts_first() {
  // At a build every entry starts in the first part (the list's order): the next branchy step
  // finds each row whose entries do not all touch stale and orders it there, with the loop's
  // own geometry (force_block, or force_block_friction at an advancing step). partner_ keeps
  // the list's order, which fixes the order of a row's sums.
  first_end_.assign(list_.offset.begin() + 1, list_.offset.end());
  if (!friction_) {
    partner_first_ = partner_;
    return;
  }
  // With friction the rows hold entries (the history is the entry's), int32 as the partners.
  if (list_.index.size() > static_cast<std::size_t>(INT32_MAX))
    throw std::length_error("DemSystem: more than 2^31 neighbour-list entries");
  entry_first_.resize(list_.index.size());
  for (std::size_t e = 0; e < entry_first_.size(); ++e)
    entry_first_[e] = static_cast<std::int32_t>(e);
}

// The pair forces of the rows of block b: partner shares go to the partner's accumulator or to
// the block's foreign slot, the rows' own sums to their accumulators. Only this block's rows and
// slots are written, and in an order fixed by the list alone.
//
// kCompact: each row's touching entries are first gathered (branch-free) into a short buffer,
// then the law runs on them alone. The branchy loop (if not touching, next entry) costs a
// mispredicted branch per entry the predictor cannot foresee; it seems to learn the pattern
// of a whole step when the list is short (same entries, same outcomes step after step), not
// when it is long (inferred from timings; no hardware counters were available). So the
// branchy loop visits each row's contacts first (partner_first_), which at nu = 0.82,
// N = 9261 takes a fifth off one thread's step; at nu = 0.64 the compact form stays faster
// (docs/performance.md "Contacts first in each row"). Both forms give the same bits; the step
// chooses by timing (DemSystem::step_impl).
template <bool kStress, bool kCompact>
void DemSystem::force_block(std::size_t b, bool handed) {
  const std::size_t n = p_.size();
  const Eigen::Vector3d L = cell_.lengths();
  // A pair is handled as whole 4-double records: one vector operation per record instead of
  // three scalar ones. The fourth lanes carry the radii (positions) and zeros (velocities, the
  // shifts, D), so that of the branch vector l holds r_i - r_j: it never enters a sum (r2 and
  // l . v_rel add lanes 0-2 only) and leaves only an unused value in the accumulators' lane 3.
  V4 shift[27];
  image_shifts(L, shift);
  const NormalContact law = options_.material.contact();
  const V4 D = {last_D_[0], last_D_[1], last_D_[2], 0.0};
  double* __restrict P = pos4_.data();
  double* __restrict W = va8_.data();
  double* __restrict A = va8_.data() + 4;
  const std::int64_t* __restrict off = list_.offset.data();
  const std::int32_t* __restrict idx = partner_.data();
  std::int32_t* __restrict first = partner_first_.data();
  double* __restrict sd = stress_scratch_.data();
  const std::size_t lo = block_lo_[b], hi = block_lo_[b + 1];
  for (std::size_t i = lo; i < hi; ++i) store4(A + 8 * i, V4{});
  const double* __restrict X = slot_in_.data();
  for (std::size_t s = slot_lo_[b]; s < slot_lo_[b + 1]; ++s) {
    const std::size_t r = n + s, j = static_cast<std::size_t>(slot_particle_[s]);
    const bool in = handed && slot_handed_[s];
    store4(P + 4 * r, load4(in ? X + 8 * s : P + 4 * j) - shift[slot_code_[s]]);
    store4(W + 8 * r, load4(in ? X + 8 * s + 4 : W + 8 * j));
    store4(A + 8 * r, V4{});
  }
  for (std::size_t i = lo; i < hi; ++i) {
    const V4 pi = load4(P + 4 * i), vi = load4(W + 8 * i);
    const double ri = P[4 * i + 3];
    const std::int64_t end = off[i + 1];
    V4 fi = {}, si = {};
    // Entry e's pair (i, j): l = x_i - x_j (images: slots), r2 = |l|^2, R = r_i + r_j.
    struct Pair {
      V4 l;
      std::size_t j;
      double r2, R;
    };
    const auto entry = [&](const std::int32_t* __restrict partners, std::int64_t e) {
      const std::size_t j = static_cast<std::size_t>(partners[e]);
      const V4 l = pi - load4(P + 4 * j);
      const V4 l2 = l * l;
      return Pair{l, j, l2[0] + l2[1] + l2[2], ri + P[4 * j + 3]};
    };
    // The force of a pair in contact: added to the row's sums, its opposite to *share (the
    // partner's accumulator).
    const auto contact = [&](const Pair& c, double* share) {
      const V4& l = c.l;
      const double d = std::sqrt(c.r2);
      const double inv = 1.0 / d;
      // The contact law (contact.hpp) as a multiple of l, with l . v_rel, v_rel the true
      // relative velocity (peculiar part plus the affine part D l).
      double* wj = W + 8 * c.j;  // the partner's velocity, then its force accumulator
      const V4 lrel = l * fused_multiply_add(D, l, vi - load4(wj));
      const double lv = lrel[0] + lrel[1] + lrel[2];
      const double s = law.force_over_distance(c.R - d, inv, lv);
      const V4 sv = {s, s, s, s};
      fi = fused_multiply_add(sv, l, fi);
      store4(share, fused_multiply_add<true>(sv, l, load4(share)));
      if constexpr (kStress) si = fused_multiply_add(l, sv * l, si);
    };
    if constexpr (kCompact) {
      // Every entry is written at the next free place, which only a touching one advances.
      constexpr std::int64_t kChunk = 64;
      // One array per field, 48 bytes per entry: a buffer of padded 64-byte Pairs measured 2-5 %
      // slower (BM_Step, compact form).
      alignas(32) V4 cl[kChunk];
      double cr2[kChunk], cR[kChunk];
      std::int32_t cj[kChunk];
      for (std::int64_t e0 = off[i]; e0 < end; e0 += kChunk) {
        const std::int64_t e1 = std::min(end, e0 + kChunk);
        std::size_t k = 0;
        for (std::int64_t e = e0; e < e1; ++e) {
          const Pair c = entry(idx, e);
          cl[k] = c.l, cr2[k] = c.r2, cR[k] = c.R, cj[k] = idx[e];
          k += c.r2 < c.R * c.R;
        }
        for (std::size_t q = 0; q < k; ++q) {
          const std::size_t j = static_cast<std::size_t>(cj[q]);
          contact(Pair{cl[q], j, cr2[q], cR[q]}, W + 8 * j + 4);
        }
      }
    } else {
      // The row's contacts first (partner_first_): the sums fi and si follow the list's order
      // as long as no entry of the second part touches. One that does (a contact made since the
      // row was ordered) makes the row take its sums again in the list's order; the partners'
      // shares need not, each goes to a record of its own. A row whose parts no longer match
      // its contacts (late, or stale: an entry of the first part no longer touches) is
      // ordered again.
      const std::int64_t split = first_end_[i];
      bool stale = false, late = false;
      for (std::int64_t e = off[i]; e < split; ++e) {
        const Pair c = entry(first, e);
        if (c.r2 >= c.R * c.R) {
          stale = true;
          continue;
        }
        contact(c, W + 8 * c.j + 4);
      }
      for (std::int64_t e = split; e < end; ++e) {
        const Pair c = entry(first, e);
        late |= c.r2 < c.R * c.R;
      }
      if (late | stale) [[unlikely]] {
        if (late) {
          for (std::int64_t e = split; e < end; ++e) {
            const Pair c = entry(first, e);
            if (c.r2 < c.R * c.R) contact(c, W + 8 * c.j + 4);
          }
          // The sums again in the list's order (the shares, given above, to a discarded record).
          alignas(32) double discard[4] = {};
          fi = V4{}, si = V4{};
          for (std::int64_t e = off[i]; e < end; ++e) {
            const Pair c = entry(idx, e);
            if (c.r2 < c.R * c.R) contact(c, discard);
          }
        }
        first_end_[i] = contacts_first(
            first, off[i], end, [&](std::int64_t e) { return idx[e]; },
            [&](std::int64_t e) {
              const Pair c = entry(idx, e);
              return c.r2 < c.R * c.R;
            });
      }
    }
    store4(A + 8 * i, load4(A + 8 * i) + fi);
    if constexpr (kStress) {
      sd[3 * i] = si[0];
      sd[3 * i + 1] = si[1];
      sd[3 * i + 2] = si[2];
    }
  }
}

template void DemSystem::force_block<false, false>(std::size_t, bool);
template void DemSystem::force_block<false, true>(std::size_t, bool);
template void DemSystem::force_block<true, false>(std::size_t, bool);
template void DemSystem::force_block<true, true>(std::size_t, bool);

}  // namespace rendulic::dem

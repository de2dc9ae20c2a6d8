// The FIRE minimiser's contact forces (fire_forces.hpp; docs/performance.md "FIRE's forces and
// the probe tools' pair search"). Every FIRE iteration of the probes' relaxation tail, the
// minimisation probes, the elastic range and the states at rest runs this loop, over ~10
// candidate pairs per particle (the minimiser's skin), about half of them touching at
// nu = 0.64.
//
// It runs over chunks of the list in two passes: (1) each candidate's branch vector by the
// minimum image, its length and overlap, four pairs at a time in the lanes of a V4 (orthorhombic
// cells; the records of four pairs transposed into one vector per component), each touching
// pair's record written at the next free place without a branch on the test; (2) the forces of
// the touching pairs in the list's order. As one loop with a branch per pair it was bound by the
// branch (mispredicted about once in two pairs at nu = 0.64) and by ~45 instructions per pair.
// This file is compiled without implicit contraction: every sum rounds as written, with a fused
// multiply-add exactly where GCC had contracted the loop before (where the hardware fuses), so
// the forces are those of that loop to the bit.
#include "fire_forces.hpp"

#include <algorithm>
#include <cmath>

#include "vec4.hpp"

namespace rendulic::dem {
using namespace vec4;
namespace {

// Rounded to an integer in the current rounding mode (std::nearbyint of each lane).
inline V4 nearby4(V4 x) {
#if defined(__AVX__)
  return reinterpret_cast<V4>(
      _mm256_round_pd(reinterpret_cast<__m256d>(x), _MM_FROUND_CUR_DIRECTION | _MM_FROUND_NO_EXC));
#else
  return V4{std::nearbyint(x[0]), std::nearbyint(x[1]), std::nearbyint(x[2]), std::nearbyint(x[3])};
#endif
}

inline V4 sqrt4(V4 x) {
#if defined(__AVX__)
  return reinterpret_cast<V4>(_mm256_sqrt_pd(reinterpret_cast<__m256d>(x)));
#else
  return V4{std::sqrt(x[0]), std::sqrt(x[1]), std::sqrt(x[2]), std::sqrt(x[3])};
#endif
}

// |l| of a branch vector: (l_x^2 + l_y^2) then l_z^2 added with one rounding, as GCC had
// contracted Eigen's squaredNorm.
inline double length(const Eigen::Vector3d& l) {
  return std::sqrt(fused_multiply_add(l(2), l(2), l(0) * l(0) + l(1) * l(1)));
}

}  // namespace

double fire_contact_forces(const PackingData& packing, const Eigen::Matrix3d& h_inv,
                           const std::vector<FirePair>& pairs, const NormalContact& law,
                           FireScratch& scratch, Eigen::MatrixX3d& force, double* sum_contact_force,
                           int* n_contacts) {
  const int n = packing.size();
  scratch.record.resize(4 * static_cast<std::size_t>(n));
  scratch.force.assign(4 * static_cast<std::size_t>(n), 0.0);
  double* __restrict P = scratch.record.data();
  double* __restrict F = scratch.force.data();
  for (int i = 0; i < n; ++i) {
    for (int a = 0; a < 3; ++a) P[4 * i + a] = packing.positions(i, a);
    P[4 * i + 3] = packing.radii(i);
  }
  const bool orthorhombic = packing.cell.is_orthorhombic();
  const Eigen::Vector3d h_diag = packing.cell.h.diagonal(), h_inv_diag = h_inv.diagonal();
  // l = x_i - x_j by the minimum image (cell.hpp), in its orthorhombic form where it applies.
  const auto branch = [&](const double* pi, const double* pj) -> Eigen::Vector3d {
    const Eigen::Vector3d dx(pi[0] - pj[0], pi[1] - pj[1], pi[2] - pj[2]);
    return orthorhombic ? minimum_image_orthorhombic(h_diag, h_inv_diag, dx)
                        : minimum_image(packing.cell, h_inv, dx);
  };
  double energy = 0.0, sum_f = 0.0;
  int contacts = 0;
  const double half_k = 0.5 * law.k;
  constexpr std::size_t kChunk = 64;
  // Touching pairs of a chunk: (l_x, l_y, l_z, f / |l|), the overlap and the pair; 4 more places
  // for the lanes of the last quadruple that do not touch.
  alignas(32) double touching[kChunk + 4][4];
  double overlap[kChunk + 4];
  FirePair who[kChunk + 4];
  const V4 k4 = V4{} + law.k;  // NormalContact::elastic_force: k delta
  const V4 hi_x = V4{} + h_inv_diag(0), hi_y = V4{} + h_inv_diag(1), hi_z = V4{} + h_inv_diag(2);
  const V4 h_x = V4{} + h_diag(0), h_y = V4{} + h_diag(1), h_z = V4{} + h_diag(2);
  for (std::size_t e0 = 0; e0 < pairs.size(); e0 += kChunk) {
    const std::size_t e1 = std::min(pairs.size(), e0 + kChunk);
    std::size_t k = 0, e = e0;
    if (orthorhombic) {
      for (; e + 4 <= e1; e += 4) {
        const FirePair* c = pairs.data() + e;
        const auto pi = components(P + 4 * c[0].i, P + 4 * c[1].i, P + 4 * c[2].i, P + 4 * c[3].i);
        const auto pj = components(P + 4 * c[0].j, P + 4 * c[1].j, P + 4 * c[2].j, P + 4 * c[3].j);
        V4 sx = (pi[0] - pj[0]) * hi_x, sy = (pi[1] - pj[1]) * hi_y, sz = (pi[2] - pj[2]) * hi_z;
        const V4 lx = (sx - nearby4(sx)) * h_x, ly = (sy - nearby4(sy)) * h_y,
                 lz = (sz - nearby4(sz)) * h_z;
        const V4 r = sqrt4(fused_multiply_add(lz, lz, lx * lx + ly * ly));
        const V4 delta = (pi[3] + pj[3]) - r;
        // The force over |l| for all four lanes (one vector division, which is what the divider
        // takes longest over, instead of one per touching pair).
        const V4 s = (k4 * delta) / r;
        const auto touch = delta > 0.0;
        // Lane q's record goes to place k + (touching lanes before q), in lane order: a lane
        // that does not touch is overwritten by the next one (or left past the count).
        const std::size_t k1 = k + (touch[0] & 1), k2 = k1 + (touch[1] & 1),
                          k3 = k2 + (touch[2] & 1);
        const V4 xy02 = __builtin_shuffle(lx, ly, Mask4{0, 4, 2, 6});
        const V4 xy13 = __builtin_shuffle(lx, ly, Mask4{1, 5, 3, 7});
        const V4 zs02 = __builtin_shuffle(lz, s, Mask4{0, 4, 2, 6});
        const V4 zs13 = __builtin_shuffle(lz, s, Mask4{1, 5, 3, 7});
        store4(touching[k], __builtin_shuffle(xy02, zs02, Mask4{0, 1, 4, 5}));
        overlap[k] = delta[0], who[k] = c[0];
        store4(touching[k1], __builtin_shuffle(xy13, zs13, Mask4{0, 1, 4, 5}));
        overlap[k1] = delta[1], who[k1] = c[1];
        store4(touching[k2], __builtin_shuffle(xy02, zs02, Mask4{2, 3, 6, 7}));
        overlap[k2] = delta[2], who[k2] = c[2];
        store4(touching[k3], __builtin_shuffle(xy13, zs13, Mask4{2, 3, 6, 7}));
        overlap[k3] = delta[3], who[k3] = c[3];
        k = k3 + (touch[3] & 1);
      }
    }
    for (; e < e1; ++e) {
      const FirePair c = pairs[e];
      const double *pi = P + 4 * c.i, *pj = P + 4 * c.j;
      const Eigen::Vector3d l = branch(pi, pj);
      const double r = length(l);
      const double delta = (pi[3] + pj[3]) - r;
      touching[k][0] = l(0), touching[k][1] = l(1), touching[k][2] = l(2);
      touching[k][3] = law.elastic_force(delta) / r;
      overlap[k] = delta, who[k] = c;
      k += delta > 0.0;
    }
    for (std::size_t q = 0; q < k; ++q) {
      const FirePair c = who[q];
      const V4 l = load4(touching[q]);
      const double delta = overlap[q];
      const double f = law.elastic_force(delta);
      const V4 s = V4{} + l[3];
      // The force s l on i, -s l on j: x and y as a product then a sum, z with one rounding
      // (the rounding of the earlier loop). The records' fourth lanes gather unused values.
      // (i's sum in a register across its row: 8 % faster at nu = 0.82, 9 % slower at 0.64.)
      const V4 sl = s * l;
      double* fi = F + 4 * c.i;
      double* fj = F + 4 * c.j;
      const V4 a = load4(fi), b = load4(fj);
      store4(fi, __builtin_shuffle(a + sl, fused_multiply_add(s, l, a), Mask4{0, 1, 6, 3}));
      store4(fj, __builtin_shuffle(b - sl, fused_multiply_add<true>(s, l, b), Mask4{0, 1, 6, 3}));
      energy = fused_multiply_add(half_k * delta, delta,
                                  energy);  // k delta^2 / 2 (NormalContact::energy)
      sum_f += f;
      ++contacts;
    }
  }
  for (int i = 0; i < n; ++i)
    for (int a = 0; a < 3; ++a) force(i, a) = F[4 * i + a];
  *sum_contact_force = sum_f;
  *n_contacts = contacts;
  return energy;
}

}  // namespace rendulic::dem

// Four-double records of the DEM force loops (dem_system.cpp, pair_loop.cpp, and FIRE's
// fire_forces.cpp): one vector operation per record instead of three scalar ones
// (docs/performance.md "Engine speed"), and the transpositions between the records of four
// particles and one vector per component. Internal to the dem module's sources.
#pragma once

#if defined(__AVX__)
#include <immintrin.h>
#endif

#include <Eigen/Core>
#include <array>
#include <cmath>
#include <cstdint>

#include "rendulic/dem/neighbor_list.hpp"

// Four doubles handled as one vector (AVX with -march=native, SSE pairs otherwise); records are
// 32-byte aligned (CacheAlignedAllocator). Without AVX, GCC notes at every use that passing
// such a vector by value has another ABI than with it; these helpers are internal to the
// module's sources and inlined, so no ABI is involved.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wpsabi"
#endif

namespace rendulic::dem::vec4 {

typedef double V4 __attribute__((vector_size(32)));
inline V4 load4(const double* p) { return *reinterpret_cast<const V4*>(p); }
inline void store4(double* p, V4 v) { *reinterpret_cast<V4*>(p) = v; }
// A four-double half of a 64-byte line, and a whole line (two halves), written past the
// caches, and the fence that makes such writes visible before a barrier: the team's hand-offs
// (DemSystem::hand_in and hand_out, docs/performance.md "Hand-offs past the caches").
inline void stream_half_line(double* p, V4 a) {
#if defined(__AVX__)
  _mm256_stream_pd(p, reinterpret_cast<__m256d>(a));
#else
  store4(p, a);
#endif
}
inline void stream_line(double* p, V4 a, V4 b) {
  stream_half_line(p, a);
  stream_half_line(p + 4, b);
}
inline void stream_fence() {
#if defined(__AVX__)
  _mm_sfence();
#endif
}
inline V4 cross3(V4 a, V4 b) {
  return V4{a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0], 0.0};
}

// a * b + c (kNegate: c - a * b), rounded once where the hardware fuses (FMA) and never fused
// otherwise. The files that use them are compiled without implicit contraction
// (-ffp-contract=off, dem/CMakeLists.txt: pair_loop.cpp, fire_forces.cpp), so a sum's rounding
// is fixed by the source, not by what the compiler fuses around it in each context: the pair
// loop's forms and a row's two ways of taking its sums give the same bits. (c - a * b as
// (-a) * b + c costs an extra negation: 3 % of the engine's step.)
template <bool kNegate = false>
inline V4 fused_multiply_add(V4 a, V4 b, V4 c) {
#if defined(__FMA__)
  const __m256d x = reinterpret_cast<__m256d>(a), y = reinterpret_cast<__m256d>(b),
                z = reinterpret_cast<__m256d>(c);
  return reinterpret_cast<V4>(kNegate ? _mm256_fnmadd_pd(x, y, z) : _mm256_fmadd_pd(x, y, z));
#else
  return kNegate ? c - a * b : a * b + c;
#endif
}
template <bool kNegate = false>
inline double fused_multiply_add(double a, double b, double c) {
#if defined(__FMA__)
  return kNegate ? std::fma(-a, b, c) : std::fma(a, b, c);
#else
  return kNegate ? c - a * b : a * b + c;
#endif
}

// The 4 x 4 transpositions between records (rows: x, y, z, fourth lane) of four entries and
// their components (one vector each). Built from the records' halves (loads into and stores
// from either half of a vector, then one in-lane interleave per component), not from whole
// records: a lane-crossing shuffle (vshuff64x2) per component made pass (2) 40 % slower.
typedef double V2 __attribute__((vector_size(16)));
inline V2 load2(const double* p) { return *reinterpret_cast<const V2*>(p); }
inline void store2(double* p, V2 v) { *reinterpret_cast<V2*>(p) = v; }
using Mask4 = long long __attribute__((vector_size(32)));
// A record's half (x, y or z, fourth lane) of a and of c in the halves of one vector: one load
// and one load-and-insert (GCC writes the generic form as a load and a lane-crossing shuffle).
inline V4 halves(const double* a, const double* c) {
#if defined(__AVX__)
  return _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_load_pd(a)), _mm_load_pd(c), 1);
#else
  return __builtin_shufflevector(load2(a), load2(c), 0, 1, 2, 3);
#endif
}
inline std::array<V4, 4> components(const double* a, const double* b, const double* c,
                                    const double* d) {
  const V4 ac0 = halves(a, c), bd0 = halves(b, d), ac1 = halves(a + 2, c + 2),
           bd1 = halves(b + 2, d + 2);
  return {__builtin_shuffle(ac0, bd0, Mask4{0, 4, 2, 6}),
          __builtin_shuffle(ac0, bd0, Mask4{1, 5, 3, 7}),
          __builtin_shuffle(ac1, bd1, Mask4{0, 4, 2, 6}),
          __builtin_shuffle(ac1, bd1, Mask4{1, 5, 3, 7})};
}
// The halves of v into a and c (a store and an extract-and-store).
inline void store_halves(V4 v, double* a, double* c) {
#if defined(__AVX__)
  _mm_store_pd(a, _mm256_castpd256_pd128(v));
  _mm_store_pd(c, _mm256_extractf128_pd(v, 1));
#else
  store2(a, __builtin_shufflevector(v, v, 0, 1));
  store2(c, __builtin_shufflevector(v, v, 2, 3));
#endif
}
inline void records(V4 x, V4 y, V4 z, V4 w, double* a, double* b, double* c, double* d) {
  store_halves(__builtin_shuffle(x, y, Mask4{0, 4, 2, 6}), a, c);
  store_halves(__builtin_shuffle(x, y, Mask4{1, 5, 3, 7}), b, d);
  store_halves(__builtin_shuffle(z, w, Mask4{0, 4, 2, 6}), a + 2, c + 2);
  store_halves(__builtin_shuffle(z, w, Mask4{1, 5, 3, 7}), b + 2, d + 2);
}

// The 27 periodic image shifts of the cell as 4-double records (fourth lane 0), by image code.
inline void image_shifts(const Eigen::Vector3d& L, V4* shift) {
  for (int c = 0; c < 27; ++c) {
    const Eigen::Vector3d s = NeighborList::shift(static_cast<std::uint8_t>(c));
    shift[c] = V4{s[0] * L[0], s[1] * L[1], s[2] * L[2], 0.0};
  }
}

}  // namespace rendulic::dem::vec4

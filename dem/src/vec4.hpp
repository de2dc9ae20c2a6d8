// Four-double records of the DEM engine's force loops (dem_system.cpp, pair_loop.cpp): one
// vector operation per record instead of three scalar ones (docs/performance.md "Engine
// speed"). Internal to the dem module's sources.
#pragma once

#include <Eigen/Core>
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
inline V4 cross3(V4 a, V4 b) {
  return V4{a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0], 0.0};
}

// The 27 periodic image shifts of the cell as 4-double records (fourth lane 0), by image code.
inline void image_shifts(const Eigen::Vector3d& L, V4* shift) {
  for (int c = 0; c < 27; ++c) {
    const Eigen::Vector3d s = NeighborList::shift(static_cast<std::uint8_t>(c));
    shift[c] = V4{s[0] * L[0], s[1] * L[1], s[2] * L[2], 0.0};
  }
}

}  // namespace rendulic::dem::vec4

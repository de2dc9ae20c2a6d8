// Neighbour search for strongly polydisperse packings (w = 3), docs/physics.md section 1 and
// docs/dem.md "Physics and numerics". A half Verlet list (each pair once, found through a half
// stencil of bins; the force loop adds the pair force to both ends) built from a cell list whose
// bins are at least the largest interaction range max_i 2 (r_i + h_i) wide. Each entry keeps the
// periodic image (a shift code) of its pair at build time; positions are not wrapped between
// builds, and since the affine remap scales positions and cell lengths alike, the stored image
// stays the right one until the next build.
//
// Per-particle skins. Particle i carries a half skin h_i >= skin / 2, and a pair is listed when
// |l| < r_i + r_j + h_i + h_j. At nu = 0.82 under loading a few particles (rattlers, small
// spheres in loose cages) move ten times farther between builds than the median one, and with
// one common skin they alone set the rebuild interval. Here a particle that moved far during
// the last interval gets a wider skin for the next one (see choose_half_skins), capped so that
// r_i + h_i never exceeds r_max + skin / 2: the bins, and hence the cost of a build, stay those
// of the common skin. The skins change only the cost, never the forces: the rule below is exact.
//
// Rebuild rule. Later the cell is scaled by S = diag(L / L_build) and particle i has moved
// non-affinely by u_i = x_i - S x_i(build). An unlisted pair then has
// |l'| >= s_min (R + h_i + h_j) - u_i - u_j with s_min = min_a S_aa and R = r_i + r_j <= 2 r_max,
// so no contact is missed while e_i + e_j < -(1 - s_min) 2 r_max for every pair, e_i =
// u_i - s_min h_i. must_rebuild() tests the sum of the two largest e_i against that bound.
#pragma once

#include <Eigen/Dense>
#include <cmath>
#include <cstdint>
#include <vector>

#include "rendulic/dem/particles.hpp"

namespace rendulic::dem {

// The rebuild rule's two largest excesses: e1 >= e2 stay the two largest values seen.
inline void keep_two_largest(double e, double& e1, double& e2) {
  if (e > e1)
    e2 = e1, e1 = e;
  else if (e > e2)
    e2 = e;
}

// keep_two_largest(sqrt(u2) - t, e1, e2) for an excess e_i = u_i - s_min h_i (u2 = u_i^2,
// t = s_min h_i >= 0), without the square root where the value cannot reach e2, as for most
// particles of a step: e1 and e2 come out the same bit for bit. The test is conservative by far
// more than the roundings of e2 + t, b * b and the square root (a few units in the last place),
// so a skipped value is below e2 as computed (docs/performance.md "A third host").
inline void keep_two_largest_excess(double u2, double t, double& e1, double& e2) {
  const double b = (e2 + t) - 1e-12 * (std::abs(e2) + t);
  if (b > 0.0 && u2 < (1.0 - 1e-12) * (b * b)) return;
  keep_two_largest(std::sqrt(u2) - t, e1, e2);
}

class NeighborList {
 public:
  // Builds from positions that lie inside [0, L) on every axis, every half skin skin / 2.
  // Throws InputError if the cell is too small for one periodic image per pair
  // (L_a <= 2 (2 r_max + skin)).
  void build(const Particles& p, const Eigen::Vector3d& lengths, double skin);
  // The same with per-particle half skins (each >= skin / 2 and r_i + h_i <= r_max + skin / 2),
  // on `threads` threads (0: omp_get_max_threads()); the list does not depend on them.
  void build(const Particles& p, const Eigen::Vector3d& lengths, double skin,
             std::vector<double> half_skins, int threads = 0);
  // Whether per-particle half skins fit `skin` as build() asks (a saved list's half skins
  // fit the skin it was made with only).
  static bool half_skins_fit(const std::vector<double>& radius, double skin,
                             const std::vector<double>& half_skins);

  // Reference state of the last build (for the rebuild rule and for bit-identical restarts).
  const std::vector<double>& ref_x() const { return ref_x_; }
  const std::vector<double>& ref_y() const { return ref_y_; }
  const std::vector<double>& ref_z() const { return ref_z_; }
  const Eigen::Vector3d& ref_lengths() const { return ref_lengths_; }
  const std::vector<double>& half_skins() const { return half_skin_; }
  double skin() const { return skin_; }
  double r_max() const { return r_max_; }
  std::int64_t builds() const { return builds_; }

  // s_min = min_a L_a / L_build,a: the e_i of the rebuild rule are u_i - s_min h_i.
  double s_min(const Eigen::Vector3d& lengths) const {
    return (lengths.array() / ref_lengths_.array()).minCoeff();
  }
  // True when the list may miss a contact (see the rule above); e1 >= e2 are the two largest
  // excesses e_i = u_i - s_min h_i.
  bool must_rebuild(double e1, double e2, const Eigen::Vector3d& lengths) const;

  // CSR: neighbours of i are entries [offset[i], offset[i+1]).
  std::vector<std::int64_t> offset;
  std::vector<std::int32_t> index;
  std::vector<std::uint8_t> shift_code;  // (sx+1) + 3 (sy+1) + 9 (sz+1), s in {-1, 0, 1}
  // l = x_i - x_j + s * L for the pair's image.
  static Eigen::Vector3d shift(std::uint8_t code) {
    return {double(code % 3) - 1.0, double((code / 3) % 3) - 1.0, double(code / 9) - 1.0};
  }

 private:
  std::vector<double> ref_x_, ref_y_, ref_z_, half_skin_;
  Eigen::Vector3d ref_lengths_ = Eigen::Vector3d::Ones();
  double skin_ = 0.0;
  double r_max_ = 0.0;
  std::int64_t builds_ = 0;
};

// Half skins for the next list from the non-affine displacements u of the interval that just
// ended: h_i = h0 clamp(u_i / u_ref, 1, ...) with h0 = skin / 2 and u_ref the displacement of the
// 95th percentile, capped at kMaxSkinRatio h0 and at r_max + h0 - r_i (bins unchanged).
inline constexpr double kMaxSkinRatio = 4.0;
std::vector<double> choose_half_skins(const std::vector<double>& u,
                                      const std::vector<double>& radius, double skin);

}  // namespace rendulic::dem

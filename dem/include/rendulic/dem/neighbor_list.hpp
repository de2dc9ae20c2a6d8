// Neighbour search for strongly polydisperse packings (w = 3), physics.md section 1 and issue 3
// item 4. A half Verlet list (each pair once, found through a half stencil of bins; the force
// loop adds the pair force to both ends) built from a cell list whose bins are at least the largest
// interaction range 2 r_max + skin wide. Each entry keeps the periodic image (a shift code) of its
// pair at build time; positions are not wrapped between builds, and since the affine remap scales
// positions and cell lengths alike, the stored image stays the right one until the next build.
//
// Rebuild rule. At build time every pair with |l| < r_i + r_j + skin is listed. Later the cell
// is scaled by S = diag(L / L_build) and particle i has moved non-affinely by
// u_i = x_i - S x_i(build). An unlisted pair then has |l'| >= s_min (R + skin) - 2 u_max with
// s_min = min_a S_aa, R = r_i + r_j <= 2 r_max. No contact is missed while
// 2 u_max + (1 - s_min) 2 r_max < s_min skin, which is the test of must_rebuild().
#pragma once

#include <Eigen/Dense>
#include <cstdint>
#include <vector>

#include "rendulic/dem/particles.hpp"

namespace rendulic::dem {

class NeighborList {
 public:
  // Builds from positions that lie inside [0, L) on every axis. Throws InputError if the cell
  // is too small for one periodic image per pair (L_a <= 2 (2 r_max + skin)).
  void build(const Particles& p, const Eigen::Vector3d& lengths, double skin);

  // Reference state of the last build (for the rebuild rule and for bit-identical restarts).
  const std::vector<double>& ref_x() const { return ref_x_; }
  const std::vector<double>& ref_y() const { return ref_y_; }
  const std::vector<double>& ref_z() const { return ref_z_; }
  const Eigen::Vector3d& ref_lengths() const { return ref_lengths_; }
  double skin() const { return skin_; }
  double r_max() const { return r_max_; }
  std::int64_t builds() const { return builds_; }

  // True when the list may miss a contact (see the rule above); u_max is the largest
  // non-affine displacement since the build.
  bool must_rebuild(double u_max, const Eigen::Vector3d& lengths) const;

  // CSR: neighbours of i are entries [offset[i], offset[i+1]).
  std::vector<std::int64_t> offset;
  std::vector<std::int32_t> index;
  std::vector<std::uint8_t> shift_code;  // (sx+1) + 3 (sy+1) + 9 (sz+1), s in {-1, 0, 1}
  // l = x_i - x_j + s * L for the pair's image.
  static Eigen::Vector3d shift(std::uint8_t code) {
    return {double(code % 3) - 1.0, double((code / 3) % 3) - 1.0, double(code / 9) - 1.0};
  }

 private:
  std::vector<double> ref_x_, ref_y_, ref_z_;
  Eigen::Vector3d ref_lengths_ = Eigen::Vector3d::Ones();
  double skin_ = 0.0;
  double r_max_ = 0.0;
  std::int64_t builds_ = 0;
};

}  // namespace rendulic::dem

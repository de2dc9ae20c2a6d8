// Contact geometry of a periodic sphere packing, for the probe tools (docs/physics.md sections
// 1-3): a cell given by its 3x3 matrix h (columns = cell vectors; orthorhombic = diag(L)), the
// minimum-image branch vector l = x_i - x_j of every pair within a cut-off (cell lists over
// fractional coordinates), and the static stress (paper eq. 1) and fabric (eq. 2) of the
// frictionless linear contact law. The probe tools (linear response, energy minimisation, probe
// checks) use this self-contained geometry so that they can check the DEM engine independently
// rather than share its code paths.
#pragma once

#include <Eigen/Dense>
#include <algorithm>
#include <utility>
#include <vector>

#include "rendulic/dem/cell.hpp"

namespace rendulic::dem {

// Particles of a periodic packing: plain data, as stored under /states/<label>.
struct PackingData {
  Eigen::MatrixX3d positions;  // [N,3], m
  Eigen::VectorXd radii;       // [N], m
  PeriodicCell cell;           // any cell (cell.hpp)
  int size() const { return static_cast<int>(radii.size()); }
  double volume() const { return cell.volume(); }
  // The homogeneous deformation x -> F x of positions and cell (F the deformation gradient):
  // the one affine map of the probe tools (an affine probe step, apply_affine_strain()).
  void deform(const Eigen::Matrix3d& F) {
    positions = positions * F.transpose();
    cell.deform(F);
  }
  // An orthorhombic cell of lengths L.
  static PackingData orthorhombic(Eigen::MatrixX3d positions, Eigen::VectorXd radii,
                                  const Eigen::Vector3d& cell_lengths);
};

// A candidate pair: i < j, l = x_i - x_j (minimum image), distance |l|.
struct PairGeometry {
  int i = 0;
  int j = 0;
  Eigen::Vector3d l = Eigen::Vector3d::Zero();
  double distance = 0.0;
  double overlap = 0.0;  // r_i + r_j - |l|, negative when apart
};

// Every pair with r_i + r_j - |l| > -skin (skin >= 0), each once, in a deterministic order
// (sorted by (i, j)). Throws InputError if the cell is too thin for a unique minimum image
// (perpendicular width < 2 (2 r_max + skin)) or the data are inconsistent.
std::vector<PairGeometry> find_pairs(const PackingData& packing, double skin);
// The same pairs in no particular order, into `pairs` (cleared first; a caller that searches
// often keeps its capacity: the FIRE minimiser's rebuilds).
void find_pairs_unordered(const PackingData& packing, double skin,
                          std::vector<PairGeometry>& pairs);
// find_pairs' order (i, j) for pairs of n particles, each stored as make(pair) (a type with a
// member j) into `out`: counted into rows by i, each row then sorted by j (a few pairs), which
// costs a fraction of a sort of the whole list.
template <class T, class Make>
void order_pairs(const std::vector<PairGeometry>& pairs, int n, std::vector<T>& out, Make make) {
  std::vector<int> start(static_cast<std::size_t>(n) + 1, 0);
  for (const PairGeometry& c : pairs) ++start[c.i + 1];
  for (int i = 0; i < n; ++i) start[i + 1] += start[i];
  out.resize(pairs.size());
  for (const PairGeometry& c : pairs) out[start[c.i]++] = make(c);
  // start[i] is now where row i + 1 begins
  for (int i = 0, begin = 0; i < n; begin = start[i++])
    std::sort(out.begin() + begin, out.begin() + start[i],
              [](const T& a, const T& b) { return a.j < b.j; });
}

// Static stress (compression positive, Pa) and fabric of the contacts with overlap > 0:
// sigma = (1/V) sum l (x) f, F = (1/V) sum_p V_p sum_{c in p} n n. Particles with
// include[p] == 0 (if `include` is given) and all their contacts are left out, and so are
// contacts with overlap <= min_overlap (a minimiser resolves forces only down to its
// tolerance: below it a touching contact is indistinguishable from an open one).
struct StressFabric {
  Eigen::Matrix3d stress = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d fabric = Eigen::Matrix3d::Zero();
  int contacts = 0;
  double elastic_energy = 0.0;  // sum k delta^2 / 2, J
};
StressFabric measure_stress_fabric(const PackingData& packing, double k,
                                   const std::vector<char>* include = nullptr,
                                   double min_overlap = 0.0);

// The fabric of eq. 2 over a given set of pairs (i, j) of `packing`, whatever their overlap:
// (1/V) sum (V_i + V_j) n n with n the unit minimum-image branch vector of each pair.
Eigen::Matrix3d fabric_of_pairs(const PackingData& packing,
                                const std::vector<std::pair<int, int>>& pairs);

// The change of the fabric of eq. 2 between two configurations of the same particles, split
// with the contact set of the first held fixed (docs/probes.md "Fabric split"). With F_S(x, V)
// the fabric of the pairs S at positions x in volume V, S the contacts of `before`:
//   volume   = F_S(x0, V0) (V0 / V1 - 1)         the same normals in the new volume,
//   rotation = F_S(x1, V1) - F_S(x0, V0) V0 / V1  the normals of the same pairs, rotated,
//   contacts = (F1 - F0) - volume - rotation       contacts made and lost (the structure).
// The three sum to F1 - F0 exactly; F0 and F1 are the fabrics as measured (over the contact
// sets of each configuration), F_S(x0, V0) equals F0 when S is the set F0 was measured on.
struct FabricSplit {
  Eigen::Matrix3d volume = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d contacts = Eigen::Matrix3d::Zero();
};
FabricSplit split_fabric_change(const PackingData& before, const PackingData& after,
                                const std::vector<std::pair<int, int>>& contacts_before,
                                const Eigen::Matrix3d& fabric_before,
                                const Eigen::Matrix3d& fabric_after);

}  // namespace rendulic::dem

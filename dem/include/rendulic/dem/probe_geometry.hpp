// Contact geometry of a periodic sphere packing, for the probe tools (physics.md sections 1-3):
// a cell given by its 3x3 matrix h (columns = cell vectors; orthorhombic = diag(L)), the
// minimum-image branch vector l = x_i - x_j of every pair within a cut-off (cell lists over
// fractional coordinates), and the static stress (paper eq. 1) and fabric (eq. 2) of the
// frictionless linear contact law. The probe tools (linear response, energy minimisation,
// probe checks) use this self-contained geometry so that they can check the DEM engine
// independently rather than share its code paths.
#pragma once

#include <Eigen/Dense>
#include <vector>

namespace rendulic::dem {

// Particles of a periodic packing: plain data, as stored under /states/<label>.
struct PackingData {
  Eigen::MatrixX3d positions;                          // [N,3], m
  Eigen::VectorXd radii;                               // [N], m
  Eigen::Matrix3d cell = Eigen::Matrix3d::Identity();  // columns: cell vectors, m
  int size() const { return static_cast<int>(radii.size()); }
  double volume() const { return cell.determinant(); }
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

// Minimum-image vector of a separation in a (nearly orthorhombic) cell.
Eigen::Vector3d minimum_image(const Eigen::Matrix3d& cell, const Eigen::Matrix3d& cell_inverse,
                              const Eigen::Vector3d& separation);

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

}  // namespace rendulic::dem

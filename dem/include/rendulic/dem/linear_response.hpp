// Exact small-strain response of the contact network of a relaxed packing (docs/probes.md "Linear
// response: what exactly is computed"; docs/physics.md sections 1, 3, 5): no dynamics, one sparse
// factorisation.
//
// Energy U = sum_c phi(|l_c|), phi = k delta^2 / 2, with l_c = (I + E) l_c0 + u_i - u_j for a
// homogeneous kinematic strain E (extension positive) and non-affine displacements u. For a
// given E the displacements minimise U: H du = -Xi dE, H = sum_c B_c^T K_c B_c the Hessian of
// the contact network with the contact block K_c = k n n - (f/|l|) (I - n n) (the second term
// is the geometric, pre-stress, term of a loaded contact). The static stress of eq. 1 in the
// DEFORMED cell, sigma = (1/V) sum l (x) f, then changes by (tension positive)
//   V d sigma_T = sum_c [(k |l| + f)(n.dl) n n - f (dl (x) n + n (x) dl)] - V sigma_T tr dE
// with dl = dE l + du_i - du_j: the Born term (k l^2 + f l) nnnn, the pre-stress terms
// -(dE sigma_T + sigma_T dE) + sigma_T tr dE (volume change of the cell), and the non-affine
// relaxation -Xi^T H^-1 Xi. Converted to the conventions of docs/physics.md (strain and stress
// compression positive) the matrix keeps its entries: d_sigma = C d_eps (Mandel).
// So C is the rate of the Cauchy stress as a dynamic probe measures it, sigma_after -
// sigma_before with sigma evaluated in the deformed cell, NOT the second derivative of the
// energy density (they differ by the pre-stress terms, which the lattice test pins down).
//
// The fabric of eq. 2 changes only by the rotation of the contact normals (no contact opens
// or closes in the linear response), dn = (I - n n) dl / |l|, and by the volume change:
// V dF = sum_c (V_i + V_j)(dn (x) n + n (x) dn) - V F tr dE.
//
// Rattlers (fewer than min_contacts contacts, removed iteratively), particles whose local
// stiffness block is singular (local zero modes), and their contacts are left out of C, of the
// reference stress/fabric and of dF: they carry no force at equilibrium and their contacts are
// not a linear response. The three global translations are removed by holding one backbone
// particle fixed (the right-hand sides sum to zero, so this only fixes the gauge). A
// remaining zero or negative pivot (a floppy or unstable network) is reported as a failure
// with its reason, never as numbers.
//
// Frictional packings (the overload with LinearFriction; docs/probes.md "Linear response of a
// frictional packing"): the small-strain limit of the engine's tangential spring
// (contact.hpp, TangentialContact): translations and rotations of the backbone particles,
// a tangential spring k_t on every contact (treated as sticking), the terms of the existing
// tangential force as the contact turns, and a non-symmetric Jacobian solved by sparse LU.
// Contacts at the Coulomb limit are counted: the response is then direction-dependent.
#pragma once

#include <Eigen/Dense>
#include <limits>
#include <string>
#include <vector>

#include "rendulic/core/conventions.hpp"
#include "rendulic/dem/probe_geometry.hpp"

namespace rendulic::dem {

// Sparse factorisation of the Hessian. kAuto: CHOLMOD's supernodal Cholesky where the build
// has it (RENDULIC_WITH_CHOLMOD; ~2 s at N = 9261), else Eigen's simplicial LDL^T (same
// result, about 20x slower at N = 9261, fine for small packings).
enum class LinearSolver { kAuto, kCholmod, kSimplicialLdlt };
// True when the build links CHOLMOD (SuiteSparse).
bool linear_response_has_cholmod();

struct LinearResponseOptions {
  double k = 1e8;  // normal stiffness, kg/s^2
  LinearSolver solver = LinearSolver::kAuto;
  // A particle with fewer contacts is a rattler (docs/physics.md section 3).
  int min_contacts = 4;
  // A particle whose local block sum_c K_c has its smallest eigenvalue below
  // floppy_tolerance * k cannot be held by its contacts (e.g. 4 coplanar contacts) and is
  // removed like a rattler. Frictional packings: such a particle is kept and only its local
  // zero modes are held (docs/probes.md "Linear response of a frictional packing").
  double floppy_tolerance = 1e-6;
  // Pivots (D of LDL^T, squared diagonal of the Cholesky factor) below pivot_tolerance
  // times the largest pivot mean a global zero mode.
  double pivot_tolerance = 1e-12;
  // A failed Cholesky (not positive definite) is diagnosed by an LDL^T that counts the
  // negative and zero pivots, for Hessians up to this many unknowns (it is slow beyond).
  int diagnose_max_dof = 20000;
  bool IsValid(std::string* why) const;
};

struct LinearResponse {
  bool ok = false;
  std::string message;  // why not ok, or a summary line
  // d_sigma = stiffness * d_eps (Mandel, compression positive, Pa).
  Matrix6d stiffness = Matrix6d::Constant(std::numeric_limits<double>::quiet_NaN());
  // The affine part alone (Born + pre-stress terms, no relaxation).
  Matrix6d affine_stiffness = Matrix6d::Constant(std::numeric_limits<double>::quiet_NaN());
  // d_F = fabric_stiffness * d_eps (Mandel, dimensionless per unit strain), and its two parts
  // (no contact opens or closes): the volume change, fabric_volume_stiffness d_eps = F tr(d_eps),
  // and the rotation of the normals (affine and non-affine), fabric_rotation_stiffness.
  Matrix6d fabric_stiffness = Matrix6d::Constant(std::numeric_limits<double>::quiet_NaN());
  Matrix6d fabric_volume_stiffness = Matrix6d::Constant(std::numeric_limits<double>::quiet_NaN());
  Matrix6d fabric_rotation_stiffness = Matrix6d::Constant(std::numeric_limits<double>::quiet_NaN());
  // Reference stress (Pa, compression positive) and fabric of the backbone contacts.
  Eigen::Matrix3d stress = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d fabric = Eigen::Matrix3d::Zero();
  double volume = 0.0;
  int n_particles = 0;
  int n_rattlers = 0;  // rattlers and locally floppy particles together
  // Frictionless: of the rattlers, those removed as locally floppy. Frictional: backbone
  // particles whose local zero modes are held (none of them is removed).
  int n_floppy = 0;
  int n_contacts = 0;  // all contacts with overlap > 0
  int n_backbone_contacts = 0;
  std::vector<char> backbone;  // [N], 1 for the particles kept
  // Largest net force on a backbone particle over the mean contact force: how far from
  // equilibrium the reference state is (the linear response assumes equilibrium).
  double residual_force_ratio = 0.0;
  int n_negative_pivots = 0;     // -1 where not counted (large failed Cholesky)
  int n_zero_pivots = 0;         // -1 where not counted
  double min_pivot_ratio = 0.0;  // smallest / largest pivot
  // Where there are negative pivots (counted): [N,3] displacements u along which the energy
  // curves down, u^T H u = the most negative pivot (zero rows on rattlers and on the particle
  // held fixed); empty otherwise. leave_saddle() (rest.hpp) moves a saddle's packing along it.
  Eigen::MatrixX3d negative_direction;
  std::string solver;           // "cholmod" or "simplicial_ldlt"
  double solve_residual = 0.0;  // max over the 6 columns of |H u - b| / |b|
  double seconds_assembly = 0.0;
  double seconds_factorisation = 0.0;
  double seconds_total = 0.0;
  // Taken at the state's energy minimum, the state as given having none (a DEM state's residual
  // forces made the Hessian indefinite; probe_campaign.hpp, state_linear_response).
  bool minimised_first = false;
  // Frictional response only (LinearFriction given): contacts of the backbone whose tangential
  // force is at the Coulomb limit (|f_t| >= (1 - coulomb_tolerance) mu f_n), treated as
  // sticking. Where there is one, the true response depends on the loading direction and
  // `stiffness` is that of the directions in which they all stick (an upper bound).
  bool frictional = false;
  int n_coulomb_limit = 0;
  double coulomb_limit_fraction = 0.0;  // of the backbone contacts
  // With rolling resistance: backbone contacts whose rolling spring is at its limit mu_r f_n
  // (the same tolerance), treated as sticking too.
  int n_rolling_limit = 0;
  bool direction_dependent() const { return n_coulomb_limit > 0 || n_rolling_limit > 0; }

  // d_sigma (Pa) and d_F for a strain increment (compression positive).
  Eigen::Matrix3d stress_increment(const Eigen::Matrix3d& d_eps) const {
    return from_mandel(stiffness * to_mandel(d_eps));
  }
  Eigen::Matrix3d fabric_increment(const Eigen::Matrix3d& d_eps) const {
    return from_mandel(fabric_stiffness * to_mandel(d_eps));
  }
};

// Throws InputError on inconsistent data or invalid options; an unjammed, floppy or unstable
// network gives ok == false with the reason.
LinearResponse linear_response(const PackingData& packing, const LinearResponseOptions& options);

// The tangential state of a frictional packing at rest: the engine's material (k_t, mu) and the
// tangential spring xi of each contact in contact with history (pair i < j, xi the
// displacement of i's contact point relative to j's: the engine's Contact::spring). Contacts
// without an entry have xi = 0 (formed, not yet sheared).
struct LinearFriction {
  double k_t = 0.0;  // tangential stiffness, kg/s^2
  double mu = 0.0;   // Coulomb coefficient (> 0)
  // Rolling resistance (docs/physics.md; off at mu_r = 0): the rolling spring's stiffness k_r
  // and limit mu_r f_n, and the rolling springs (pair i < j; the same for either order).
  double k_r = 0.0;
  double mu_r = 0.0;
  // A contact with |f_t| >= (1 - coulomb_tolerance) mu f_n is at the Coulomb limit (and one
  // with |f_r| >= (1 - coulomb_tolerance) mu_r f_n at its rolling limit).
  double coulomb_tolerance = 1e-3;
  struct Spring {
    int i = 0, j = 0;
    Eigen::Vector3d xi = Eigen::Vector3d::Zero();
  };
  std::vector<Spring> springs;
  std::vector<Spring> rolling_springs;
  bool rolling() const { return mu_r > 0; }
  bool IsValid(std::string* why) const;
};
// The linear response of a frictional packing at rest (options.min_contacts is the caller's:
// rattler_min_contacts(true) for a frictional packing, dem/measures.hpp). The Jacobian is not
// symmetric (the engine's turned spring is not conservative): solved by sparse LU, so
// n_negative_pivots and n_zero_pivots are -1 (not counted) and options.solver is not used.
LinearResponse linear_response(const PackingData& packing, const LinearResponseOptions& options,
                               const LinearFriction& friction);

}  // namespace rendulic::dem

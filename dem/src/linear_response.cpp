// Linear response of the contact network: rattler removal, sparse Hessian
// with the geometric term, one LDL^T factorisation for the six strain components, stiffness
// and fabric rates. The derivation is in linear_response.hpp. Frictional packings (the
// LinearFriction overload, docs/probes.md "Linear response of a frictional packing") have
// their own path: rotations, tangential springs, a non-symmetric Jacobian and sparse LU; the
// frictionless path does not share its code, so its results are unchanged.
#include "rendulic/dem/linear_response.hpp"

#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseLU>
#include <array>
#include <chrono>
#include <cmath>
#include <map>
#include <memory>
#include <numbers>
#include <sstream>

#ifdef RENDULIC_WITH_CHOLMOD
#include <Eigen/CholmodSupport>
#endif

#include "rendulic/core/errors.hpp"
#include "rendulic/dem/contact.hpp"

namespace rendulic::dem {

bool LinearResponseOptions::IsValid(std::string* why) const {
  auto fail = [&](const char* m) {
    if (why) *why = m;
    return false;
  };
  if (!(k > 0.0) || !std::isfinite(k)) return fail("linear response: k must be positive");
  if (min_contacts < 1) return fail("linear response: min_contacts must be >= 1");
  if (!(floppy_tolerance >= 0.0) || !(floppy_tolerance < 1.0))
    return fail("linear response: floppy_tolerance must be in [0, 1)");
  if (!(pivot_tolerance > 0.0) || !(pivot_tolerance < 1.0))
    return fail("linear response: pivot_tolerance must be in (0, 1)");
  return true;
}

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// The weight of a contact in the fabric (eq. 2): the volumes of its two spheres.
double pair_volume(const PackingData& packing, int i, int j) {
  const auto volume = [&](int p) {
    return 4.0 / 3.0 * std::numbers::pi * std::pow(packing.radii(p), 3);
  };
  return volume(i) + volume(j);
}

constexpr const char* kNoBackbone =
    "no rigid backbone: every particle is a rattler (the packing is not jammed)";

// Largest net load (a row of `net`) on a kept particle over the mean contact force.
template <class Net>
double residual_ratio(const Net& net, const std::vector<char>& keep, double mean_f) {
  double max_net = 0.0;
  for (Eigen::Index p = 0; p < net.rows(); ++p) {
    if (keep[p]) max_net = std::max(max_net, net.row(p).norm());
  }
  return max_net / mean_f;
}

struct BackboneContact {
  int i, j;
  Eigen::Vector3d n;  // unit normal, from j to i
  double r;           // |l|
  double f;           // k delta > 0
};

// BackboneContact Hessian block: d^2 phi(|l|) / dl dl = k n n - (f/r)(I - n n).
Eigen::Matrix3d contact_block(const BackboneContact& c, const NormalContact& law) {
  const Eigen::Matrix3d nn = c.n * c.n.transpose();
  return law.stiffness() * nn - (c.f / c.r) * (Eigen::Matrix3d::Identity() - nn);
}

// Strain basis tensor whose Mandel vector is the unit vector a.
Eigen::Matrix3d mandel_basis(int a) {
  Vector6d e = Vector6d::Zero();
  e(a) = 1.0;
  return from_mandel(e);
}

using SparseMatrix = Eigen::SparseMatrix<double>;

// The six solves m u = rhs are accepted when the largest relative residual is below this; above
// it the matrix is nearly singular and no response is given.
constexpr double kMaxSolveResidual = 1e-6;

double largest_relative_residual(const SparseMatrix& m, const Eigen::MatrixXd& u,
                                 const Eigen::MatrixXd& rhs) {
  double largest = 0.0;
  for (Eigen::Index a = 0; a < rhs.cols(); ++a) {
    const double b = rhs.col(a).norm();
    if (b > 0.0) largest = std::max(largest, (m * u.col(a) - rhs.col(a)).norm() / b);
  }
  return largest;
}

std::string inaccurate_solve(double residual, const char* matrix) {
  std::ostringstream os;
  os << "linear response: the sparse solve is inaccurate (relative residual " << residual
     << "): " << matrix << " is nearly singular";
  return os.str();
}
using Ldlt = Eigen::SimplicialLDLT<SparseMatrix, Eigen::Lower, Eigen::AMDOrdering<int>>;

// LDL^T with the count of negative and (relatively) zero pivots; nullptr if it failed.
std::unique_ptr<Ldlt> count_pivots(const SparseMatrix& hessian, double tolerance,
                                   LinearResponse* out) {
  auto ldlt = std::make_unique<Ldlt>(hessian);
  if (ldlt->info() != Eigen::Success) return nullptr;
  const Eigen::VectorXd d = ldlt->vectorD();
  const double d_max = d.cwiseAbs().maxCoeff();
  out->min_pivot_ratio = d.minCoeff() / d_max;
  out->n_zero_pivots = out->n_negative_pivots = 0;
  for (Eigen::Index r = 0; r < d.size(); ++r) {
    if (std::abs(d(r)) <= tolerance * d_max) {
      ++out->n_zero_pivots;
    } else if (d(r) < 0.0) {
      ++out->n_negative_pivots;
    }
  }
  return ldlt;
}

// The direction of the most negative pivot r of P H P^T = L D L^T: L^T y = e_r gives
// y^T L D L^T y = D_r < 0, so x = P^-1 y has x^T H x = D_r. On the dofs (3 per entry of dof),
// laid out as [N,3] with zero rows where dof < 0.
Eigen::MatrixX3d negative_direction(const Ldlt& ldlt, const std::vector<int>& dof) {
  const Eigen::VectorXd d = ldlt.vectorD();
  Eigen::Index r = 0;
  d.minCoeff(&r);
  Eigen::VectorXd y = Eigen::VectorXd::Zero(d.size());
  y(r) = 1.0;
  ldlt.matrixU().solveInPlace(y);
  const Eigen::VectorXd x = ldlt.permutationPinv() * y;
  Eigen::MatrixX3d u = Eigen::MatrixX3d::Zero(static_cast<Eigen::Index>(dof.size()), 3);
  for (std::size_t p = 0; p < dof.size(); ++p)
    if (dof[p] >= 0) u.row(static_cast<Eigen::Index>(p)) = x.segment<3>(dof[p]).transpose();
  return u;
}

#ifdef RENDULIC_WITH_CHOLMOD
// CHOLMOD's reciprocal condition estimate, (min diag L / max diag L)^2, is the pivot ratio.
class SupernodalLlt : public Eigen::CholmodSupernodalLLT<SparseMatrix, Eigen::Lower> {
 public:
  double pivot_ratio() { return cholmod_rcond(this->m_cholmodFactor, &this->cholmod()); }
};
bool cholmod_solve(const SparseMatrix& hessian, const Eigen::MatrixXd& rhs, Eigen::MatrixXd* u,
                   double* pivot_ratio) {
  SupernodalLlt llt;
  // An indefinite Hessian is an expected outcome here (the caller minimises and retries, or
  // records the state as unstable): CHOLMOD's own stderr warning would only alarm the user.
  llt.cholmod().print = 0;
  llt.compute(hessian);
  if (llt.info() != Eigen::Success) return false;
  *pivot_ratio = llt.pivot_ratio();
  *u = llt.solve(rhs);
  return true;
}
#else
bool cholmod_solve(const SparseMatrix&, const Eigen::MatrixXd&, Eigen::MatrixXd*, double*) {
  throw InputError("linear response: solver 'cholmod' requested but this build has no CHOLMOD");
}
#endif

}  // namespace

bool linear_response_has_cholmod() {
#ifdef RENDULIC_WITH_CHOLMOD
  return true;
#else
  return false;
#endif
}

LinearResponse linear_response(const PackingData& packing, const LinearResponseOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) throw InputError(why);
  const auto t_start = Clock::now();
  LinearResponse out;
  const int n = packing.size();
  const NormalContact law{options.k, 0.0};  // at rest: the spring alone
  out.n_particles = n;
  out.volume = packing.volume();

  std::vector<BackboneContact> all;
  for (const PairGeometry& p : find_pairs(packing, 0.0)) {
    if (p.overlap > 0.0)
      all.push_back({p.i, p.j, p.l / p.distance, p.distance, law.elastic_force(p.overlap)});
  }
  out.n_contacts = static_cast<int>(all.size());

  // Rattlers and locally floppy particles, removed iteratively: removing one lowers the
  // contact count of its neighbours.
  std::vector<char>& keep = out.backbone;
  keep.assign(n, 1);
  std::vector<int> count(n);
  std::vector<Eigen::Matrix3d> local(n);
  for (bool changed = true; changed;) {
    changed = false;
    std::fill(count.begin(), count.end(), 0);
    for (auto& b : local) b.setZero();
    for (const BackboneContact& c : all) {
      if (!keep[c.i] || !keep[c.j]) continue;
      ++count[c.i];
      ++count[c.j];
      const Eigen::Matrix3d kc = contact_block(c, law);
      local[c.i] += kc;
      local[c.j] += kc;
    }
    for (int p = 0; p < n; ++p) {
      if (!keep[p]) continue;
      if (count[p] < options.min_contacts) {
        keep[p] = 0;
        changed = true;
        ++out.n_rattlers;
      } else if (Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(local[p], Eigen::EigenvaluesOnly)
                     .eigenvalues()(0) < options.floppy_tolerance * law.stiffness()) {
        keep[p] = 0;
        changed = true;
        ++out.n_rattlers;
        ++out.n_floppy;
      }
    }
  }
  std::vector<BackboneContact> contacts;
  for (const BackboneContact& c : all) {
    if (keep[c.i] && keep[c.j]) contacts.push_back(c);
  }
  out.n_backbone_contacts = static_cast<int>(contacts.size());

  // Reference stress and fabric of the backbone (compression positive), residual forces.
  Eigen::MatrixX3d net = Eigen::MatrixX3d::Zero(n, 3);
  double sum_f = 0.0;
  for (const BackboneContact& c : contacts) {
    const Eigen::Matrix3d nn = c.n * c.n.transpose();
    out.stress += (c.f * c.r) * nn;
    out.fabric += pair_volume(packing, c.i, c.j) * nn;
    net.row(c.i) += c.f * c.n.transpose();
    net.row(c.j) -= c.f * c.n.transpose();
    sum_f += c.f;
  }
  out.stress /= out.volume;
  out.fabric /= out.volume;

  // Degrees of freedom: 3 per backbone particle except the first, held fixed (gauge).
  std::vector<int> dof(n, -1);
  int n_dof = 0, pinned = -1;
  for (int p = 0; p < n; ++p) {
    if (!keep[p]) continue;
    if (pinned < 0) {
      pinned = p;
      continue;
    }
    dof[p] = n_dof;
    n_dof += 3;
  }
  if (contacts.empty() || n_dof == 0) {
    out.message = kNoBackbone;
    out.seconds_total = seconds_since(t_start);
    return out;
  }
  const double mean_f = sum_f / static_cast<double>(contacts.size());
  out.residual_force_ratio = residual_ratio(net, keep, mean_f);

  // Hessian (lower triangle is what the factorisation reads; both are filled for clarity of
  // the block structure) and the six right-hand sides b_a = Xi E_a.
  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(contacts.size() * 36 + 9 * static_cast<std::size_t>(n));
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(n_dof, 6);
  std::array<Eigen::Matrix3d, 6> basis;
  for (int a = 0; a < 6; ++a) basis[a] = mandel_basis(a);
  auto add_block = [&](int row, int col, const Eigen::Matrix3d& b) {
    if (row < 0 || col < 0) return;
    for (int r = 0; r < 3; ++r)
      for (int s = 0; s < 3; ++s) triplets.emplace_back(row + r, col + s, b(r, s));
  };
  for (const BackboneContact& c : contacts) {
    const Eigen::Matrix3d kc = contact_block(c, law);
    const int di = dof[c.i], dj = dof[c.j];
    add_block(di, di, kc);
    add_block(dj, dj, kc);
    add_block(di, dj, -kc);
    add_block(dj, di, -kc);
    const Eigen::Vector3d l = c.r * c.n;
    for (int a = 0; a < 6; ++a) {
      // Force-balance change of the affine motion: +K dl on i, -K dl on j.
      const Eigen::Vector3d g = kc * (basis[a] * l);
      if (di >= 0) rhs.block<3, 1>(di, a) -= g;
      if (dj >= 0) rhs.block<3, 1>(dj, a) += g;
    }
  }
  SparseMatrix hessian(n_dof, n_dof);
  hessian.setFromTriplets(triplets.begin(), triplets.end());
  triplets.clear();
  triplets.shrink_to_fit();
  out.seconds_assembly = seconds_since(t_start);

  const auto t_factor = Clock::now();
  const bool use_cholmod = options.solver == LinearSolver::kCholmod ||
                           (options.solver == LinearSolver::kAuto && linear_response_has_cholmod());
  Eigen::MatrixXd u;
  auto fail = [&](const std::string& reason) {
    out.message = reason;
    out.seconds_total = seconds_since(t_start);
    return out;
  };
  auto pivot_failure = [&]() {
    std::ostringstream os;
    os << "linear response: the contact network is "
       << (out.n_negative_pivots > 0 ? "unstable" : "floppy") << " (" << out.n_negative_pivots
       << " negative and " << out.n_zero_pivots
       << " zero pivots of the Hessian after removing rattlers and translations): no elastic "
          "response exists";
    return fail(os.str());
  };
  if (use_cholmod) {
    out.solver = "cholmod";
    if (!cholmod_solve(hessian, rhs, &u, &out.min_pivot_ratio)) {
      out.seconds_factorisation = seconds_since(t_factor);
      if (n_dof > options.diagnose_max_dof) {
        out.n_negative_pivots = out.n_zero_pivots = -1;
        return fail(
            "linear response: the Hessian is not positive definite (the contact network is "
            "unstable or floppy): no elastic response exists");
      }
      const auto ldlt = count_pivots(hessian, options.pivot_tolerance, &out);
      if (ldlt && out.n_negative_pivots > 0)
        out.negative_direction = negative_direction(*ldlt, dof);
      return pivot_failure();
    }
    out.seconds_factorisation = seconds_since(t_factor);
    if (out.min_pivot_ratio <= options.pivot_tolerance) {
      out.n_zero_pivots = -1;  // at least one; CHOLMOD gives the ratio, not the count
      return fail(
          "linear response: the Hessian is singular to working precision (a floppy "
          "mode survived rattler removal): no elastic response exists");
    }
  } else {
    out.solver = "simplicial_ldlt";
    const auto ldlt = count_pivots(hessian, options.pivot_tolerance, &out);
    out.seconds_factorisation = seconds_since(t_factor);
    if (!ldlt) return fail("linear response: the LDL^T factorisation of the Hessian failed");
    if (out.n_negative_pivots > 0) out.negative_direction = negative_direction(*ldlt, dof);
    if (out.n_zero_pivots > 0 || out.n_negative_pivots > 0) return pivot_failure();
    u = ldlt->solve(rhs);
  }
  out.solve_residual = largest_relative_residual(hessian, u, rhs);
  if (!u.allFinite() || !(out.solve_residual < kMaxSolveResidual))
    return fail(inaccurate_solve(out.solve_residual, "the Hessian"));

  // Stress and fabric rates in the tension frame (dE), column by column.
  const Eigen::Matrix3d sigma_t = -out.stress;
  Matrix6d c_full, c_affine, g_full, g_volume, g_rotation;
  for (int a = 0; a < 6; ++a) {
    const Eigen::Matrix3d& de = basis[a];
    Eigen::Matrix3d ds_full = Eigen::Matrix3d::Zero(), ds_affine = Eigen::Matrix3d::Zero();
    Eigen::Matrix3d df = Eigen::Matrix3d::Zero();
    for (const BackboneContact& c : contacts) {
      const Eigen::Vector3d l = c.r * c.n;
      const Eigen::Vector3d dl_affine = de * l;
      Eigen::Vector3d dl = dl_affine;
      if (dof[c.i] >= 0) dl += u.block<3, 1>(dof[c.i], a);
      if (dof[c.j] >= 0) dl -= u.block<3, 1>(dof[c.j], a);
      auto rate = [&](const Eigen::Vector3d& x) -> Eigen::Matrix3d {
        const Eigen::Matrix3d nx = c.n * x.transpose();
        return ((law.stiffness() * c.r + c.f) * c.n.dot(x)) * (c.n * c.n.transpose()) -
               c.f * (nx + nx.transpose());
      };
      ds_full += rate(dl);
      ds_affine += rate(dl_affine);
      const Eigen::Vector3d dn = (dl - c.n * c.n.dot(dl)) / c.r;
      const Eigen::Matrix3d dnn = dn * c.n.transpose();
      df += pair_volume(packing, c.i, c.j) * (dnn + dnn.transpose());
    }
    const double tr = de.trace();
    ds_full = ds_full / out.volume - sigma_t * tr;
    ds_affine = ds_affine / out.volume - sigma_t * tr;
    const Eigen::Matrix3d df_rotation = df / out.volume, df_volume = -out.fabric * tr;
    // d sigma_T = C_T dE with dE = -d_eps and sigma = -sigma_T: C = C_T. The fabric keeps
    // its sign, so only the strain flips: G = -G_T.
    c_full.col(a) = to_mandel(ds_full);
    c_affine.col(a) = to_mandel(ds_affine);
    g_rotation.col(a) = -to_mandel(df_rotation);
    g_volume.col(a) = -to_mandel(df_volume);
    g_full.col(a) = g_rotation.col(a) + g_volume.col(a);
  }
  out.stiffness = c_full;
  out.affine_stiffness = c_affine;
  out.fabric_stiffness = g_full;
  out.fabric_volume_stiffness = g_volume;
  out.fabric_rotation_stiffness = g_rotation;
  out.ok = true;
  std::ostringstream os;
  os << "linear response: " << n << " particles, " << out.n_rattlers << " rattlers, "
     << out.n_backbone_contacts << " backbone contacts, residual force ratio "
     << out.residual_force_ratio;
  out.message = os.str();
  out.seconds_total = seconds_since(t_start);
  return out;
}

bool LinearFriction::IsValid(std::string* why) const {
  auto fail = [&](const char* m) {
    if (why) *why = m;
    return false;
  };
  if (!(k_t > 0.0) || !std::isfinite(k_t)) return fail("linear response: k_t must be positive");
  if (!(mu > 0.0) || !std::isfinite(mu)) return fail("linear response: mu must be positive");
  if (!(mu_r >= 0.0) || !std::isfinite(mu_r)) return fail("linear response: mu_r must be >= 0");
  if (mu_r > 0.0 && (!(k_r > 0.0) || !std::isfinite(k_r)))
    return fail("linear response: k_r must be positive with rolling resistance");
  if (!(coulomb_tolerance >= 0.0) || !(coulomb_tolerance < 1.0))
    return fail("linear response: coulomb_tolerance must be in [0, 1)");
  return true;
}

namespace {

// A frictional contact at rest: its geometry, forces (on i) and levers a = r - delta / 2 (the
// engine's contact point), and the blocks of its linearised forces (docs/probes.md "Linear
// response of a frictional packing"), with theta the rotations and dl = dE l + du_i - du_j:
//   dF_i   = A dl + B_i theta_i + B_j theta_j,       dF_j = -dF_i,
//   dtau_p = C_p dl - k_t a_p P (a_i theta_i + a_j theta_j) -+ k_r a'^2 P (theta_i - theta_j)
// (p = i, j; the last term, upper sign for i, with rolling resistance: a' = a_i a_j / (a_i +
// a_j) and the rolling pseudo-force f_r, whose couple a' n x f_r on i also enters C_p).
struct FrictionalContact {
  int i = 0, j = 0;
  Eigen::Vector3d n = Eigen::Vector3d::Zero();
  double r = 0, a_i = 0, a_j = 0, f_n = 0;
  Eigen::Vector3d f_t = Eigen::Vector3d::Zero();
  bool at_limit = false;
  double a_r = 0, k_r = 0;  // a' and the rolling stiffness (0 without rolling resistance)
  Eigen::Vector3d f_r = Eigen::Vector3d::Zero();
  bool rolling_at_limit = false;
  Eigen::Matrix3d A, B_i, B_j, C_i, C_j, P;
  Eigen::Vector3d rolling_torque() const { return a_r * n.cross(f_r); }  // on i
};

Eigen::Matrix3d cross_matrix(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0, -v(2), v(1), v(2), 0, -v(0), -v(1), v(0), 0;
  return m;
}

// The engine's step, linearised (TangentialContact::turn and force, at rest): the spring turns
// with the normal, xi -> xi - (xi . dn) n, and grows by the tangential displacement of the
// contact point, s = P dl - (a_i theta_i + a_j theta_j) x n; f_t = -k_t xi; the normal force
// k delta along the turned normal; the torques -a_p n x f_t with a_p = r_p - delta / 2.
void linearise(FrictionalContact& c, double k, double k_t) {
  const Eigen::Matrix3d nn = c.n * c.n.transpose();
  c.P = Eigen::Matrix3d::Identity() - nn;
  const Eigen::Matrix3d nx = cross_matrix(c.n);
  c.A = -k * nn + (c.f_n / c.r) * c.P - (c.n * c.f_t.transpose()) / c.r - k_t * c.P;
  c.B_i = -k_t * c.a_i * nx;
  c.B_j = -k_t * c.a_j * nx;
  const Eigen::Matrix3d lever = -0.5 * c.n.cross(c.f_t) * c.n.transpose();  // d a_p = n.dl / 2
  const Eigen::Matrix3d turn = cross_matrix(c.f_t) * c.P / c.r;             // -a_p dn x f_t
  c.C_i = lever + c.a_i * turn + c.a_i * k_t * nx;
  c.C_j = lever + c.a_j * turn + c.a_j * k_t * nx;
  if (c.k_r > 0) {
    // The couple q = a' n x f_r on i (-q on j) moves with dl through its lever (d a' = alpha
    // n.dl, alpha = (a_i^2 + a_j^2) / (2 (a_i + a_j)^2)) and the turned normal (dn = P dl / r);
    // the rolling spring, turned with the normal as the tangential one, gives no torque
    // along n x n. Its growth by -a' n x (theta_i - theta_j) is the k_r a'^2 P term above.
    const double s = c.a_i + c.a_j;
    const double alpha = (c.a_i * c.a_i + c.a_j * c.a_j) / (2.0 * s * s);
    const Eigen::Matrix3d roll =
        alpha * c.n.cross(c.f_r) * c.n.transpose() - (c.a_r / c.r) * cross_matrix(c.f_r) * c.P;
    c.C_i += roll;
    c.C_j -= roll;
  }
}

}  // namespace

LinearResponse linear_response(const PackingData& packing, const LinearResponseOptions& options,
                               const LinearFriction& friction) {
  std::string why;
  if (!options.IsValid(&why) || !friction.IsValid(&why)) throw InputError(why);
  const auto t_start = Clock::now();
  LinearResponse out;
  out.frictional = true;
  out.n_negative_pivots = out.n_zero_pivots = -1;
  out.solver = "sparse_lu";
  const int n = packing.size();
  const double k = options.k, k_t = friction.k_t;
  out.n_particles = n;
  out.volume = packing.volume();

  std::map<std::pair<int, int>, Eigen::Vector3d> spring, rolling_spring;
  for (const LinearFriction::Spring& s : friction.springs) {
    if (s.i < 0 || s.j < 0 || s.i >= n || s.j >= n || s.i == s.j || !s.xi.allFinite())
      throw InputError("linear response: a tangential spring names an invalid pair");
    spring[{std::min(s.i, s.j), std::max(s.i, s.j)}] = s.i < s.j ? s.xi : Eigen::Vector3d(-s.xi);
  }
  for (const LinearFriction::Spring& s : friction.rolling_springs) {
    if (s.i < 0 || s.j < 0 || s.i >= n || s.j >= n || s.i == s.j || !s.xi.allFinite())
      throw InputError("linear response: a rolling spring names an invalid pair");
    rolling_spring[{std::min(s.i, s.j), std::max(s.i, s.j)}] = s.xi;  // either order
  }
  if (!friction.rolling() && !rolling_spring.empty())
    throw InputError("linear response: rolling springs given without rolling resistance (mu_r)");
  std::vector<FrictionalContact> all;
  for (const PairGeometry& p : find_pairs(packing, 0.0)) {
    if (!(p.overlap > 0.0)) continue;
    FrictionalContact c;
    c.i = p.i;
    c.j = p.j;
    c.n = p.l / p.distance;
    c.r = p.distance;
    c.a_i = packing.radii(p.i) - 0.5 * p.overlap;
    c.a_j = packing.radii(p.j) - 0.5 * p.overlap;
    c.f_n = k * p.overlap;
    const auto it = spring.find({p.i, p.j});
    if (it != spring.end()) {
      // The stored spring lies in the tangent plane of its last step: the engine turns it into
      // this one, then holds its force at the Coulomb limit.
      Eigen::Vector3d xi = it->second;
      TangentialContact::turn(xi, c.n);
      c.f_t = -k_t * xi;
      const double limit = friction.mu * c.f_n, ft = c.f_t.norm();
      if (ft > limit) c.f_t *= limit / ft;
      c.at_limit = ft >= (1.0 - friction.coulomb_tolerance) * limit;
    }
    if (friction.rolling()) {
      c.k_r = friction.k_r;
      c.a_r = c.a_i * c.a_j / (c.a_i + c.a_j);
      if (const auto rs = rolling_spring.find({p.i, p.j}); rs != rolling_spring.end()) {
        Eigen::Vector3d xr = rs->second;
        TangentialContact::turn(xr, c.n);
        c.f_r = -friction.k_r * xr;
        const double limit = friction.mu_r * c.f_n, fr = c.f_r.norm();
        if (fr > limit) c.f_r *= limit / fr;
        c.rolling_at_limit = fr >= (1.0 - friction.coulomb_tolerance) * limit;
      }
    }
    linearise(c, k, k_t);
    all.push_back(c);
  }
  out.n_contacts = static_cast<int>(all.size());

  // Unknowns in length units: translations u and rho = r theta (so that the blocks, and the
  // floppy test against k, have one scale); the torque rows are divided by r alike.
  auto radius = [&](int p) { return packing.radii(p); };
  using Matrix12d = Eigen::Matrix<double, 12, 12>;
  // The contact's -dG/dq, q = (u_i, rho_i, u_j, rho_j), G = (dF_i, dtau_i/r_i, dF_j, dtau_j/r_j).
  auto contact_matrix = [&](const FrictionalContact& c) {
    Matrix12d J;
    const double si = 1.0 / radius(c.i), sj = 1.0 / radius(c.j);
    const double rolling = c.k_r * c.a_r * c.a_r;
    const Eigen::Matrix3d D_ii = -(k_t * c.a_i * c.a_i + rolling) * c.P,
                          D_ij = -(k_t * c.a_i * c.a_j - rolling) * c.P,
                          D_jj = -(k_t * c.a_j * c.a_j + rolling) * c.P;
    J << c.A, si * c.B_i, -c.A, sj * c.B_j,                       //
        si * c.C_i, si * si * D_ii, -si * c.C_i, si * sj * D_ij,  //
        -c.A, -si * c.B_i, c.A, -sj * c.B_j,                      //
        sj * c.C_j, sj * si * D_ij, -sj * c.C_j, sj * sj * D_jj;
    return Matrix12d(-J);
  };
  std::vector<char>& keep = out.backbone;
  keep.assign(n, 1);
  std::vector<int> count(n);
  using Matrix6 = Eigen::Matrix<double, 6, 6>;
  for (bool changed = true; changed;) {
    changed = false;
    std::fill(count.begin(), count.end(), 0);
    for (const FrictionalContact& c : all) {
      if (!keep[c.i] || !keep[c.j]) continue;
      ++count[c.i];
      ++count[c.j];
    }
    for (int p = 0; p < n; ++p) {
      if (keep[p] && count[p] < options.min_contacts) {
        keep[p] = 0;
        changed = true;
        ++out.n_rattlers;
      }
    }
  }
  // Each particle's own 6x6 block over the contacts that remain.
  std::vector<Matrix12d> blocks(all.size());
  for (std::size_t q = 0; q < all.size(); ++q) blocks[q] = contact_matrix(all[q]);
  std::vector<Matrix6> local(n, Matrix6::Zero());
  for (std::size_t q = 0; q < all.size(); ++q) {
    const FrictionalContact& c = all[q];
    if (!keep[c.i] || !keep[c.j]) continue;
    local[c.i] += blocks[q].topLeftCorner<6, 6>();
    local[c.j] += blocks[q].bottomRightCorner<6, 6>();
  }
  // Local zero modes: a particle whose contacts cannot hold some motion of it alone (the
  // symmetric part of its 6x6 block has an eigenvalue below floppy_tolerance * k). With
  // sticking contacts that is a two-contact particle spinning about the line through its
  // contact points; the motion moves no contact point, so no contact does work on it. Such a
  // particle is a strut: it carries force along a chain and the chain's stiffness, so removing
  // it (as a frictionless floppy particle is) leaves its neighbours unbalanced and the network
  // too soft (docs/probes.md: 8-11 % softer than the dynamic probes on frictional.toml's
  // state a). It is kept, and each such mode v is held by a spring k v v^T: a mode that no
  // contact loads takes no part in the response of the others, so the spring only removes
  // the singularity (the particles' spin is then zero, which the response does not need).
  std::vector<Matrix6> hold(n, Matrix6::Zero());
  for (int p = 0; p < n; ++p) {
    if (!keep[p]) continue;
    const Eigen::SelfAdjointEigenSolver<Matrix6> eig(0.5 * (local[p] + local[p].transpose()));
    for (int e = 0; e < 6; ++e) {
      if (eig.eigenvalues()(e) >= options.floppy_tolerance * k) break;
      hold[p] += k * eig.eigenvectors().col(e) * eig.eigenvectors().col(e).transpose();
    }
    if (!hold[p].isZero(0.0)) ++out.n_floppy;
  }
  std::vector<int> backbone;  // indices into all
  for (std::size_t q = 0; q < all.size(); ++q) {
    if (keep[all[q].i] && keep[all[q].j]) backbone.push_back(static_cast<int>(q));
  }
  out.n_backbone_contacts = static_cast<int>(backbone.size());

  // Reference stress (eq. 1 with the tangential force, symmetrised: at rest its antisymmetric
  // part is the residual torque), fabric and residual forces and torques.
  Eigen::MatrixXd net = Eigen::MatrixXd::Zero(n, 6);
  double sum_f = 0.0;
  Eigen::Matrix3d stress = Eigen::Matrix3d::Zero();
  for (int q : backbone) {
    const FrictionalContact& c = all[q];
    const Eigen::Vector3d f = c.f_n * c.n + c.f_t;
    stress += (c.r * c.n) * f.transpose();
    out.fabric += pair_volume(packing, c.i, c.j) * c.n * c.n.transpose();
    net.block<1, 3>(c.i, 0) += f.transpose();
    net.block<1, 3>(c.j, 0) -= f.transpose();
    const Eigen::Vector3d nxf = c.n.cross(c.f_t);
    net.block<1, 3>(c.i, 3) -= c.a_i / radius(c.i) * nxf.transpose();
    net.block<1, 3>(c.j, 3) -= c.a_j / radius(c.j) * nxf.transpose();
    const Eigen::Vector3d couple = c.rolling_torque();
    net.block<1, 3>(c.i, 3) += couple.transpose() / radius(c.i);
    net.block<1, 3>(c.j, 3) -= couple.transpose() / radius(c.j);
    sum_f += f.norm();
    out.n_coulomb_limit += c.at_limit ? 1 : 0;
    out.n_rolling_limit += c.rolling_at_limit ? 1 : 0;
  }
  out.stress = 0.5 * (stress + stress.transpose()) / out.volume;
  out.fabric /= out.volume;
  if (!backbone.empty())
    out.coulomb_limit_fraction = out.n_coulomb_limit / static_cast<double>(backbone.size());

  // Degrees of freedom: 6 per backbone particle; the first one's translation is held (gauge).
  // Its rotation stays free: a periodic packing has no zero mode of a common rotation.
  std::vector<int> dof_u(n, -1), dof_w(n, -1);
  int n_dof = 0, pinned = -1;
  // The gauge is a particle without a held mode, so that the spring of a held mode acts on
  // all six of its components.
  for (int p = 0; p < n && pinned < 0; ++p)
    if (keep[p] && hold[p].isZero(0.0)) pinned = p;
  for (int p = 0; p < n && pinned < 0; ++p)
    if (keep[p]) pinned = p;
  for (int p = 0; p < n; ++p) {
    if (!keep[p]) continue;
    if (p != pinned) {
      dof_u[p] = n_dof;
      n_dof += 3;
    }
    dof_w[p] = n_dof;
    n_dof += 3;
  }
  if (backbone.empty() || pinned < 0) {
    out.message = kNoBackbone;
    out.seconds_total = seconds_since(t_start);
    return out;
  }
  const double mean_f = sum_f / static_cast<double>(backbone.size());
  out.residual_force_ratio = residual_ratio(net, keep, mean_f);

  std::array<Eigen::Matrix3d, 6> basis;
  for (int a = 0; a < 6; ++a) basis[a] = mandel_basis(a);
  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(backbone.size() * 144);
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(n_dof, 6);
  for (int q : backbone) {
    const FrictionalContact& c = all[q];
    const std::array<int, 4> d = {dof_u[c.i], dof_w[c.i], dof_u[c.j], dof_w[c.j]};
    for (int bi = 0; bi < 4; ++bi)
      for (int bj = 0; bj < 4; ++bj) {
        if (d[bi] < 0 || d[bj] < 0) continue;
        for (int r = 0; r < 3; ++r)
          for (int s = 0; s < 3; ++s)
            triplets.emplace_back(d[bi] + r, d[bj] + s, blocks[q](3 * bi + r, 3 * bj + s));
      }
    // The affine part of dl moves the forces and torques by the dl-columns: b = sum G_affine.
    const Eigen::Vector3d l = c.r * c.n;
    for (int a = 0; a < 6; ++a) {
      const Eigen::Vector3d dl = basis[a] * l;
      const Eigen::Vector3d g[4] = {c.A * dl, c.C_i * dl / radius(c.i), -c.A * dl,
                                    c.C_j * dl / radius(c.j)};
      for (int b = 0; b < 4; ++b)
        if (d[b] >= 0) rhs.block<3, 1>(d[b], a) += g[b];
    }
  }
  for (int p = 0; p < n; ++p) {
    if (!keep[p] || hold[p].isZero(0.0)) continue;
    const std::array<int, 2> d = {dof_u[p], dof_w[p]};
    for (int bi = 0; bi < 2; ++bi)
      for (int bj = 0; bj < 2; ++bj)
        if (d[bi] >= 0 && d[bj] >= 0)
          for (int r = 0; r < 3; ++r)
            for (int s = 0; s < 3; ++s)
              triplets.emplace_back(d[bi] + r, d[bj] + s, hold[p](3 * bi + r, 3 * bj + s));
  }
  SparseMatrix jacobian(n_dof, n_dof);
  jacobian.setFromTriplets(triplets.begin(), triplets.end());
  triplets.clear();
  triplets.shrink_to_fit();
  out.seconds_assembly = seconds_since(t_start);

  const auto t_factor = Clock::now();
  auto fail = [&](const std::string& reason) {
    out.message = reason;
    out.seconds_total = seconds_since(t_start);
    return out;
  };
  jacobian.makeCompressed();
  Eigen::SparseLU<SparseMatrix, Eigen::COLAMDOrdering<int>> lu;
  lu.compute(jacobian);
  out.seconds_factorisation = seconds_since(t_factor);
  if (lu.info() != Eigen::Success)
    return fail("linear response: the sparse LU factorisation of the frictional Jacobian failed (" +
                lu.lastErrorMessage() +
                "): the contact network is floppy, no elastic response exists");
  const Eigen::MatrixXd u = lu.solve(rhs);
  out.solve_residual = largest_relative_residual(jacobian, u, rhs);
  if (!u.allFinite() || !(out.solve_residual < kMaxSolveResidual))
    return fail(inaccurate_solve(out.solve_residual, "the frictional Jacobian"));

  // dsigma (compression positive) = (1/V) sum [dl (x) F_i + l (x) dF_i] - sigma tr dE, the
  // rate of eq. 1 as the engine measures it, symmetrised; d_eps = -dE gives C = -dsigma/dE.
  for (int a = 0; a < 6; ++a) {
    const Eigen::Matrix3d& de = basis[a];
    Eigen::Matrix3d ds_full = Eigen::Matrix3d::Zero(), ds_affine = Eigen::Matrix3d::Zero();
    Eigen::Matrix3d df = Eigen::Matrix3d::Zero();
    for (int q : backbone) {
      const FrictionalContact& c = all[q];
      const Eigen::Vector3d l = c.r * c.n, f = c.f_n * c.n + c.f_t;
      const Eigen::Vector3d dl_affine = de * l;
      Eigen::Vector3d dl = dl_affine;
      if (dof_u[c.i] >= 0) dl += u.block<3, 1>(dof_u[c.i], a);
      if (dof_u[c.j] >= 0) dl -= u.block<3, 1>(dof_u[c.j], a);
      const Eigen::Vector3d th_i = u.block<3, 1>(dof_w[c.i], a) / radius(c.i);
      const Eigen::Vector3d th_j = u.block<3, 1>(dof_w[c.j], a) / radius(c.j);
      const Eigen::Vector3d dF = c.A * dl + c.B_i * th_i + c.B_j * th_j;
      ds_full += dl * f.transpose() + l * dF.transpose();
      ds_affine += dl_affine * f.transpose() + l * (c.A * dl_affine).transpose();
      const Eigen::Vector3d dn = (dl - c.n * c.n.dot(dl)) / c.r;
      const Eigen::Matrix3d dnn = dn * c.n.transpose();
      df += pair_volume(packing, c.i, c.j) * (dnn + dnn.transpose());
    }
    const double tr = de.trace();
    // (eval: a matrix plus its own transpose must not be written into itself.)
    ds_full = (0.5 * (ds_full + ds_full.transpose()) / out.volume - out.stress * tr).eval();
    ds_affine = (0.5 * (ds_affine + ds_affine.transpose()) / out.volume - out.stress * tr).eval();
    out.stiffness.col(a) = -to_mandel(Eigen::Matrix3d(ds_full));
    out.affine_stiffness.col(a) = -to_mandel(Eigen::Matrix3d(ds_affine));
    out.fabric_rotation_stiffness.col(a) = -to_mandel(Eigen::Matrix3d(df / out.volume));
    out.fabric_volume_stiffness.col(a) = to_mandel(Eigen::Matrix3d(out.fabric * tr));
    out.fabric_stiffness.col(a) =
        out.fabric_rotation_stiffness.col(a) + out.fabric_volume_stiffness.col(a);
  }
  out.ok = true;
  std::ostringstream os;
  os << "linear response (frictional): " << n << " particles, " << out.n_rattlers << " rattlers, "
     << out.n_backbone_contacts << " backbone contacts, " << out.n_coulomb_limit
     << " at the Coulomb limit, ";
  if (friction.rolling()) os << out.n_rolling_limit << " at the rolling limit, ";
  os << out.n_floppy << " struts with their spin held, residual force ratio "
     << out.residual_force_ratio;
  out.message = os.str();
  out.seconds_total = seconds_since(t_start);
  return out;
}

}  // namespace rendulic::dem

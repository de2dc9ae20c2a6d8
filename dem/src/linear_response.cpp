// Linear response of the contact network: rattler removal, sparse Hessian
// with the geometric term, one LDL^T factorisation for the six strain components, stiffness
// and fabric rates. The derivation is in linear_response.hpp.
#include "rendulic/dem/linear_response.hpp"

#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>
#include <array>
#include <chrono>
#include <cmath>
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
  auto particle_volume = [&](int p) {
    return 4.0 / 3.0 * std::numbers::pi * std::pow(packing.radii(p), 3);
  };
  for (const BackboneContact& c : contacts) {
    const Eigen::Matrix3d nn = c.n * c.n.transpose();
    out.stress += (c.f * c.r) * nn;
    out.fabric += (particle_volume(c.i) + particle_volume(c.j)) * nn;
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
    out.message = "no rigid backbone: every particle is a rattler (the packing is not jammed)";
    out.seconds_total = seconds_since(t_start);
    return out;
  }
  const double mean_f = sum_f / static_cast<double>(contacts.size());
  double max_net = 0.0;
  for (int p = 0; p < n; ++p) {
    if (keep[p]) max_net = std::max(max_net, net.row(p).norm());
  }
  out.residual_force_ratio = max_net / mean_f;

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
      count_pivots(hessian, options.pivot_tolerance, &out);
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
    if (out.n_zero_pivots > 0 || out.n_negative_pivots > 0) return pivot_failure();
    u = ldlt->solve(rhs);
  }
  for (int a = 0; a < 6; ++a) {
    const double b = rhs.col(a).norm();
    if (b > 0.0) {
      out.solve_residual =
          std::max(out.solve_residual, (hessian * u.col(a) - rhs.col(a)).norm() / b);
    }
  }
  if (!u.allFinite() || !(out.solve_residual < 1e-6)) {
    std::ostringstream os;
    os << "linear response: the sparse solve is inaccurate (relative residual "
       << out.solve_residual << "): the Hessian is nearly singular";
    return fail(os.str());
  }

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
      df += (particle_volume(c.i) + particle_volume(c.j)) * (dnn + dnn.transpose());
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

}  // namespace rendulic::dem

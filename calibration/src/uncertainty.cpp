// Covariance, correlation and identifiability warnings (uncertainty.hpp).
#include "rendulic/calibration/uncertainty.hpp"

#include <cmath>
#include <limits>
#include <sstream>

namespace rendulic::calibration {

bool IdentifiabilityOptions::IsValid(std::string* why) const {
  if (!(rank_tolerance > 0.0 && rank_tolerance < 1.0) || !(condition_warning > 1.0) ||
      !(correlation_warning > 0.0 && correlation_warning <= 1.0) ||
      !(relative_stderr_warning > 0.0)) {
    if (why) *why = "identifiability thresholds out of range";
    return false;
  }
  return true;
}

Uncertainty estimate_uncertainty(const Eigen::MatrixXd& J, const Eigen::VectorXd& r,
                                 const std::vector<std::string>& names, const Eigen::VectorXd& p,
                                 const Eigen::VectorXd& dp_dz,
                                 const IdentifiabilityOptions& options) {
  Uncertainty u;
  const int n = static_cast<int>(J.rows()), k = static_cast<int>(J.cols());
  const double inf = std::numeric_limits<double>::infinity();
  u.n_residuals = n;
  u.dof = n - k;
  u.covariance = Eigen::MatrixXd::Zero(k, k);
  u.stderr_z = Eigen::VectorXd::Constant(k, inf);
  u.correlation = Eigen::MatrixXd::Identity(k, k);
  u.determined.assign(k, true);
  u.no_effect.assign(k, false);
  // Column normalisation: makes the rank and condition tests independent of parameter units.
  Eigen::VectorXd norms = J.colwise().norm().transpose();
  for (int j = 0; j < k; ++j) {
    if (!(norms(j) > 0.0)) {
      u.determined[j] = false;
      u.no_effect[j] = true;
      u.warnings.push_back("parameter '" + names[j] +
                           "' does not affect the fitted data at all: the data cannot "
                           "determine it (fix it, or add data that depend on it)");
      norms(j) = 1.0;
    }
  }
  const Eigen::MatrixXd Jn = J * norms.cwiseInverse().asDiagonal();
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(Jn, Eigen::ComputeThinV);
  const Eigen::VectorXd s = svd.singularValues();
  const double smax = s.size() ? s(0) : 0.0;
  u.rank = 0;
  for (int i = 0; i < s.size(); ++i)
    if (s(i) > options.rank_tolerance * smax) ++u.rank;
  u.condition_number = u.rank == k && s(k - 1) > 0.0 ? smax / s(k - 1) : inf;
  const Eigen::MatrixXd V = svd.matrixV();
  // Null directions: name the parameters that move together without changing the residuals.
  for (int i = u.rank; i < k; ++i) {
    std::ostringstream w;
    w << "rank-deficient: the data cannot determine the combination";
    for (int j = 0; j < k; ++j)
      if (std::abs(V(j, i)) > 0.1) {
        w << " " << (V(j, i) > 0 ? "+" : "-") << std::abs(V(j, i)) << "*" << names[j];
        u.determined[j] = false;
      }
    w << " (in normalised working coordinates); fix one of these parameters or add data";
    u.warnings.push_back(w.str());
  }
  if (u.rank == k && u.condition_number > options.condition_warning) {
    std::ostringstream w;
    w << "ill-conditioned: condition number " << u.condition_number
      << " of the normalised Jacobian; standard errors are large and estimates fragile";
    u.warnings.push_back(w.str());
  }
  if (u.dof <= 0) {
    u.warnings.push_back(std::string("no residual degrees of freedom (") + std::to_string(n) +
                         " residuals for " + std::to_string(k) +
                         " parameters): standard errors undefined");
    return u;
  }
  u.defined = true;
  u.sigma2 = r.squaredNorm() / u.dof;
  // Pseudo-inverse of Jn^T Jn on the determined subspace.
  Eigen::MatrixXd inv = Eigen::MatrixXd::Zero(k, k);
  for (int i = 0; i < u.rank; ++i) inv += V.col(i) * V.col(i).transpose() / (s(i) * s(i));
  const Eigen::MatrixXd cov_n = u.sigma2 * inv;
  u.covariance = norms.cwiseInverse().asDiagonal() * cov_n * norms.cwiseInverse().asDiagonal();
  for (int j = 0; j < k; ++j)
    u.stderr_z(j) = u.determined[j] ? std::sqrt(std::max(u.covariance(j, j), 0.0)) : inf;
  // Correlation from the normalised pseudo-inverse (scale free; defined when sigma2 = 0 too).
  for (int a = 0; a < k; ++a)
    for (int b = 0; b < k; ++b) {
      const double d = std::sqrt(inv(a, a) * inv(b, b));
      u.correlation(a, b) = a == b ? 1.0 : (d > 0.0 ? inv(a, b) / d : 0.0);
    }
  for (int a = 0; a < k; ++a)
    for (int b = a + 1; b < k; ++b)
      if (std::abs(u.correlation(a, b)) > options.correlation_warning && u.determined[a] &&
          u.determined[b]) {
        std::ostringstream w;
        w << "parameters '" << names[a] << "' and '" << names[b] << "' are correlated ("
          << u.correlation(a, b) << "): the data determine a combination of them better than "
          << "either";
        u.warnings.push_back(w.str());
      }
  for (int j = 0; j < k; ++j) {
    if (!u.determined[j]) continue;
    const double sp = std::abs(dp_dz(j)) * u.stderr_z(j);
    if (std::abs(p(j)) > 0.0 && sp > options.relative_stderr_warning * std::abs(p(j))) {
      std::ostringstream w;
      w << "parameter '" << names[j] << "' is poorly determined: " << p(j) << " +- " << sp;
      u.warnings.push_back(w.str());
      u.determined[j] = false;
    }
  }
  return u;
}

}  // namespace rendulic::calibration

// Parameter uncertainty and identifiability from the Jacobian at the optimum (docs/calibration.md
// "Uncertainty and identifiability"). Covariance C = s^2 (J^T J)^+
// with s^2 = SSR / (n - p), computed through the SVD of the column-normalised Jacobian so that a
// rank-deficient problem gives a pseudo-inverse, its null directions, and a plain-language warning
// instead of a huge or NaN number. The same numbers as ceres::Covariance where J has full rank
// (tests/calibration cross-check them).
#pragma once

#include <Eigen/Dense>
#include <string>
#include <vector>

namespace rendulic::calibration {

struct IdentifiabilityOptions {
  // Singular values of the column-normalised Jacobian below rank_tolerance * s_max count as
  // zero: 1e-8 sits well above the ~1e-12 noise of autodiff and numeric Jacobians of a
  // well-posed problem and well below any genuinely informative direction.
  double rank_tolerance = 1e-8;
  double condition_warning = 1e6;        // cond(J_normalised) above this: ill-conditioned
  double correlation_warning = 0.99;     // |corr| above this: the pair is not separable
  double relative_stderr_warning = 0.5;  // stderr / |p| above this: poorly determined
  bool IsValid(std::string* why) const;
};

struct Uncertainty {
  bool defined = false;  // false when n <= p (no residual variance)
  int n_residuals = 0;
  int dof = 0;
  double sigma2 = 0.0;  // residual variance s^2
  int rank = 0;
  double condition_number = 0.0;  // of the column-normalised Jacobian (inf if rank-deficient)
  Eigen::MatrixXd covariance;     // of the working coordinates z (pseudo-inverse)
  Eigen::VectorXd stderr_z;       // sqrt(diag); +inf for parameters in a null direction
  Eigen::MatrixXd correlation;    // of z (equals that of p: the maps are monotone, diagonal)
  std::vector<bool> determined;   // per parameter: identifiable and not flagged
  std::vector<bool> no_effect;    // per parameter: a zero Jacobian column
  std::vector<std::string> warnings;
};

// J: n x p Jacobian dr/dz at the optimum, r the residuals, names for messages, z the values
// and dp_dz the derivative of each physical parameter (for relative errors in p).
Uncertainty estimate_uncertainty(const Eigen::MatrixXd& J, const Eigen::VectorXd& r,
                                 const std::vector<std::string>& names, const Eigen::VectorXd& p,
                                 const Eigen::VectorXd& dp_dz,
                                 const IdentifiabilityOptions& options = {});

}  // namespace rendulic::calibration

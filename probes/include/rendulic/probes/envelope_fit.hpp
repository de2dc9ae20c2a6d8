// Geometric fits of one envelope (docs/physics.md section 6): an ellipse (centre,
// semi-axes a >= b >= 0, inclination of the major axis in [0, 180) deg from the horizontal
// sqrt(2)-lateral axis), its degenerate case the line (b = 0), and the circle (a = b within
// the noise: inclination undefined, never an arbitrary angle). The ellipse fit minimises
// orthogonal distances (one latent angle per point, Ceres), starting from the affine fit
// R(theta) = c + M u(theta) when the probe directions are known and from the direct
// algebraic fit (Halir-Flusser) otherwise. Standard errors come from ceres::Covariance,
// scaled by the residual variance. The method, the shape criterion, the loss scales and
// what the errors mean are in docs/fitting.md.
#pragma once

#include <Eigen/Dense>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "rendulic/core/affine_map.hpp"
#include "rendulic/probes/envelope.hpp"

namespace rendulic {

enum class FitShape { kEllipse, kLine, kCircle, kAuto };
enum class FitLoss { kNone, kHuber, kCauchy };
// Two equivalent formulations of the orthogonal-distance ellipse fit (docs/fitting.md):
// kExactDistance solves the nearest point inside each residual (variable projection, 5
// unknowns); kLatentAngles gives Ceres one latent angle per point (n + 5 unknowns). Same
// optimum; the first is faster, the second is the independent check of the tests.
enum class FitMethod { kExactDistance, kLatentAngles };

// "ellipse", "line", "circle", "auto"; and back (InputError on an unknown name).
std::string to_string(FitShape shape);
std::string to_string(FitLoss loss);
FitShape fit_shape_from_string(const std::string& name);
FitLoss fit_loss_from_string(const std::string& name);
// The shapes a caller may request (auto, ellipse, line; a circle is a finding, not a request)
// and the losses: the choices of the fits.* keys and of `rendulic fit`'s options.
const std::vector<std::string>& fit_shape_choices();
const std::vector<std::string>& fit_loss_choices();

struct FitOptions {
  // kAuto chooses line or ellipse by a parametric-bootstrap likelihood-ratio test (below),
  // then flags a circle. kCircle is never requested by callers in practice but is accepted.
  FitShape shape = FitShape::kAuto;
  FitLoss loss = FitLoss::kNone;
  // Loss scale in the units of the data (orthogonal distance at which the robust loss starts
  // to discount a point). 0: automatic, k * sigma_MAD with k = 1.345 (Huber) or 2.385
  // (Cauchy), the classical 95%-efficiency constants, sigma_MAD = 1.4826 median |d_i|.
  double loss_scale = 0.0;
  // Use the probe directions for the initial guess when the envelope has them.
  bool use_theta = true;
  bool compute_covariance = true;
  FitMethod method = FitMethod::kExactDistance;
  // Shape selection: the ellipse is kept over the line when the bootstrap p-value of the
  // statistic SSR_line / SSR_ellipse is below alpha.
  double selection_alpha = 0.01;
  int bootstrap_samples = 199;
  std::uint64_t seed = 20260521;
  // Circle flag: a - b below circle_z standard errors of (a - b) (or below a relative 1e-9).
  double circle_z = 2.0;
  int max_iterations = 200;

  bool IsValid(std::string* why) const;
};

struct EnvelopeFit {
  FitShape shape = FitShape::kEllipse;  // never kAuto
  Eigen::Vector2d center = Eigen::Vector2d::Zero();
  double a = 0.0;  // semi-major axis
  double b = 0.0;  // semi-minor axis (0 for a line)
  // Inclination of the major axis in [0, 180) deg; empty for a circle.
  std::optional<double> inclination_deg;
  // Root mean square orthogonal distance of the points to the fitted curve.
  double rms = 0.0;
  std::vector<double> residuals;  // orthogonal distance per point (unsigned)
  int n_points = 0;

  // Standard errors (1 sigma); present when the covariance was computed and is defined.
  bool has_stderr = false;
  Eigen::Vector2d center_stderr = Eigen::Vector2d::Zero();
  double a_stderr = 0.0;
  double b_stderr = 0.0;  // 0 for a line: b = 0 by construction, not estimated
  std::optional<double> inclination_stderr_deg;
  // Covariance of (cx, cy, a, b, inclination in rad); zero where not estimated.
  Eigen::Matrix<double, 5, 5> covariance = Eigen::Matrix<double, 5, 5>::Zero();

  // Shape selection: the bootstrap p-value of the line hypothesis (auto only), and a one-line
  // account of why this shape was chosen.
  std::optional<double> line_p_value;
  std::string selection_note;
  FitLoss loss = FitLoss::kNone;
  double loss_scale = 0.0;  // scale actually used (0 for kNone)
  bool converged = false;
  int iterations = 0;
  bool used_theta = false;
  // Work of the fit in point operations (one point's distance, residual or Jacobian
  // evaluation, or one comparison of two points): a machine-independent cost, which grows
  // linearly with n_points (docs/fitting.md "Cost").
  std::int64_t point_operations = 0;

  // Brief one-paragraph text report (for `rendulic fit` without --json).
  std::string BriefReport() const;
};

// Fits one envelope. InputError (naming the reason) on data that cannot be fitted: fewer than
// 5 points for an ellipse (2 for a line), non-finite values, all points coincident.
EnvelopeFit fit_envelope(const Envelope& envelope, const FitOptions& options = {});

// The pieces, exposed for tests and for callers that know the shape.
EnvelopeFit fit_ellipse(const Envelope& envelope, const FitOptions& options = {});
EnvelopeFit fit_line(const Envelope& envelope, const FitOptions& options = {});
EnvelopeFit fit_circle(const Envelope& envelope, const FitOptions& options = {});

// Initial guesses (linear algebra only, no iterations).
struct EllipseGuess {
  Eigen::Vector2d center;
  double a, b;            // b may be negative (orientation reversed); |a| >= |b| not guaranteed
  double phi;             // rad
  std::vector<double> t;  // latent angle per point
  bool ok = false;
};
// The ellipse of the affine fit R(theta) = c + M u(theta) (core/affine_map.hpp, needs theta):
// exact for a linear law plus a shift; the axes are the singular values of M.
EllipseGuess ellipse_guess_from_affine(const AffineMapFit& affine,
                                       const std::vector<double>& theta_deg);
// Direct least-squares ellipse (Halir and Flusser 1998). ok = false when the points admit no
// ellipse (collinear, too few, hyperbolic best conic).
EllipseGuess ellipse_guess_algebraic(const std::vector<Eigen::Vector2d>& points);

}  // namespace rendulic

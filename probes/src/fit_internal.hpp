// Helpers shared by the fit sources of probes/ (not installed): frames, latent angles and the
// robust noise scale used by envelope_fit.cpp, ellipse_fit.cpp and initial_guess.cpp.
#pragma once

#include <Eigen/Dense>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "rendulic/core/affine_map.hpp"
#include "rendulic/core/conventions.hpp"

namespace rendulic::fit_detail {

// Point operations done on this thread so far (EnvelopeFit::point_operations is the
// difference across one fit). Per thread: fits run in parallel over envelopes.
inline std::int64_t& point_operations() {
  thread_local std::int64_t count = 0;
  return count;
}

// The affine fit R = c + M u(theta) of core (affine_map.hpp), counted as one point operation
// per point when it is made.
inline AffineMapFit affine_fit(const std::vector<Eigen::Vector2d>& points,
                               const std::vector<double>& theta_deg) {
  if (points.size() >= 3 && theta_deg.size() == points.size())
    point_operations() += static_cast<std::int64_t>(points.size());
  return fit_affine_map(direction_vectors(theta_deg), points);
}

inline Eigen::Matrix2d rotation(double phi) {
  Eigen::Matrix2d r;
  r << std::cos(phi), -std::sin(phi), std::sin(phi), std::cos(phi);
  return r;
}

// Point of the ellipse c + R(phi) diag(a, b) (cos t, sin t).
inline Eigen::Vector2d ellipse_point(const Eigen::Vector2d& c, double a, double b, double phi,
                                     double t) {
  return c + rotation(phi) * Eigen::Vector2d(a * std::cos(t), b * std::sin(t));
}

// Latent angle of the point of the ellipse nearest to p: best of a 32-angle grid, then
// guarded Newton steps on the stationarity condition (monotone in the distance).
double nearest_latent_angle(const Eigen::Vector2d& p, const Eigen::Vector2d& c, double a, double b,
                            double phi);

// Same, by guarded Newton steps from t_start (a warm start); falls back to the grid when the
// distance is not locally convex there.
double nearest_latent_angle_from(const Eigen::Vector2d& p, const Eigen::Vector2d& c, double a,
                                 double b, double phi, double t_start);

// Orthogonal distance of p to the ellipse (via nearest_latent_angle).
double ellipse_distance(const Eigen::Vector2d& p, const Eigen::Vector2d& c, double a, double b,
                        double phi);

// 1.4826 * median(|d|): the normal-consistent robust scale of unsigned orthogonal distances.
double mad_scale(std::vector<double> d);

// Angle folded into [0, pi).
inline double fold_pi(double phi) {
  double f = std::fmod(phi, kPi);
  if (f < 0.0) f += kPi;
  if (f >= kPi) f -= kPi;
  return f;
}

}  // namespace rendulic::fit_detail

#include "rendulic/probes/envelope_fit.hpp"

namespace rendulic::fit_detail {

// Points moved to their centroid and divided by their rms distance from it, so that Ceres'
// tolerances mean the same thing for stresses in Pa and for fabric changes of 1e-6.
struct Normalized {
  Eigen::Vector2d origin = Eigen::Vector2d::Zero();
  double scale = 0.0;
  std::vector<Eigen::Vector2d> q;
};
Normalized normalize(const std::vector<Eigen::Vector2d>& points);

// A noiseless fit's residuals relative to the data's size (Normalized::scale): a sum of
// squared residuals, in units of that size squared, within rounding_ssr(n) is rounding.
constexpr double kRoundingRel = 1e-9;
inline double rounding_ssr(std::size_t n) {
  return kRoundingRel * kRoundingRel * static_cast<double>(n);
}

// Total least squares, the line fit's (line_fit.cpp): the principal axis d of the weighted
// scatter about the weighted centroid, its normal, and each point's along (s) and across (h)
// coordinates. Iteratively reweighted by fit_line for the robust losses.
struct Tls {
  Eigen::Vector2d centroid, d, nrm;
  std::vector<double> s, h;  // along and across coordinates of each point
};
Tls weighted_tls(const std::vector<Eigen::Vector2d>& q, const std::vector<double>& w);

// Sum of squared distances of the normalized points from their total-least-squares line.
// Within rounding_ssr the points are collinear: a line without a test in the automatic
// choice, no circle (its radius would be infinite), and an ellipse only with the probe
// directions, which fix the segment's length (docs/fitting.md "Shape criterion").
double line_ssr(const Normalized& nz);

// The range of a robust loss scale relative to the normalized data size. Below it, exact data
// (MAD = 0) would make every point an outlier; a given scale beyond its inverse discounts no
// point (that is --loss none), and its square, which the losses take, overflows near 1e154.
constexpr double kMinLossScale = 1e-8;
constexpr double kMaxLossScale = 1.0 / kMinLossScale;

// Result of the latent-angle least-squares fit of an ellipse (5 parameters cx, cy, a, b, phi)
// or a circle (3 parameters cx, cy, r), in normalized units, before folding to a >= b >= 0.
struct CurveFit {
  std::vector<double> params;
  std::vector<double> t;
  std::vector<double> d;  // orthogonal distances at the solution
  bool converged = false;
  int iterations = 0;
  bool cov_ok = false;
  Eigen::MatrixXd cov_unit;  // shape block of (J^T J)^+ (unit residual variance)
  double loss_scale = 0.0;   // 0 for FitLoss::kNone
  double sigma = 0.0;        // noise estimate used to scale cov_unit
};

// Ellipse from guess g (normalized units). With a robust loss and loss_scale <= 0 the scale is
// chosen from the residuals (two passes: from the guess, then from the first robust fit).
CurveFit solve_ellipse(const std::vector<Eigen::Vector2d>& q, const EllipseGuess& g, FitLoss loss,
                       double loss_scale, bool covariance, int max_iterations, FitMethod method);
CurveFit solve_circle(const std::vector<Eigen::Vector2d>& q, const Eigen::Vector2d& c, double r,
                      const std::vector<double>& t, FitLoss loss, double loss_scale,
                      bool covariance, int max_iterations);

// Best starting ellipse for the points: affine (theta) if allowed and possible, then
// Halir-Flusser, then principal axes (always succeeds for non-coincident points).
EllipseGuess best_guess(const std::vector<Eigen::Vector2d>& q, const std::vector<double>& theta,
                        bool use_theta, bool* used_theta);

// High-breakdown start for the robust losses (least median of squares): the best of many
// minimal subsets (5 points through Halir-Flusser; 3 directions through the affine fit when
// theta is used), judged by the median distance of all points (Sampson's first-order
// distance for the conic, the 2D residual for the affine law). Seeded: reproducible.
EllipseGuess robust_guess(const std::vector<Eigen::Vector2d>& q, const std::vector<double>& theta,
                          bool use_theta, std::uint64_t seed, bool* used_theta);

// Robust cost sum rho(d^2) (plain sum of squares for kNone) at the given scale.
double robust_cost(const std::vector<double>& d, FitLoss loss, double scale);

// Count of points distinct at a relative tolerance, up to `enough` (an ellipse needs five):
// at most `enough` kept points to compare each point with, so linear in the points.
int count_distinct(const std::vector<Eigen::Vector2d>& q, double tol, int enough);

}  // namespace rendulic::fit_detail

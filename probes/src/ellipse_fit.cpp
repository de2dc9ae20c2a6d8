// Geometric ellipse and circle fits with Ceres (docs/physics.md section 6).
// Each point p_i gets a latent angle t_i and two residuals p(t_i) - p_i, so the cost is the
// sum of squared orthogonal distances at the optimum (Gander, Golub and Strebel 1994), not
// the algebraic conic residual that biases thin ellipses. The semi-axes are free reals: the
// curve set {c + R(phi) diag(a, b) u(t)} is invariant under a -> -a, b -> -b and under
// (a, b, phi) -> (b, a, phi + 90 deg), so a >= b >= 0 and phi in [0, 180) are obtained by
// folding after the solve. Bounds at b = 0 instead would pin lines and thin ellipses on a
// bound where the covariance is undefined; with free signs b = 0 is an interior point.
#include <ceres/ceres.h>

#include <algorithm>
#include <cmath>
#include <memory>

#include "fit_internal.hpp"
#include "rendulic/core/conventions.hpp"
#include "rendulic/core/decimal.hpp"
#include "rendulic/core/errors.hpp"
#include "rendulic/probes/envelope_fit.hpp"

namespace rendulic {
namespace fit_detail {
namespace {

struct EllipsePointResidual {
  double x, y;
  template <typename T>
  bool operator()(const T* s, const T* t, T* r) const {
    using std::cos;
    using std::sin;
    const T cp = cos(s[4]), sp = sin(s[4]);
    const T ex = s[2] * cos(t[0]), ey = s[3] * sin(t[0]);
    r[0] = s[0] + cp * ex - sp * ey - x;
    r[1] = s[1] + sp * ex + cp * ey - y;
    return true;
  }
};

struct CirclePointResidual {
  double x, y;
  template <typename T>
  bool operator()(const T* s, const T* t, T* r) const {
    using std::cos;
    using std::sin;
    r[0] = s[0] + s[2] * cos(t[0]) - x;
    r[1] = s[1] + s[2] * sin(t[0]) - y;
    return true;
  }
};

// Signed orthogonal distance of one point to the ellipse s = (cx, cy, a, b, phi): the
// latent angle is eliminated by the nearest-point condition (warm-started from the last
// evaluation), and the derivative follows from the envelope theorem, dr/ds = -n . de/ds at
// fixed t, since p - e(t*) is normal to the curve. Its Jacobian is the Schur complement of
// the latent-angle problem, so the 5 x 5 covariance of this problem is the marginal
// covariance of the shape, at a fraction of the cost of the (n + 5)-square one.
class EllipseDistanceCost : public ceres::SizedCostFunction<1, 5> {
 public:
  // Distances below this fraction of the ellipse's size are rounding: their direction is noise.
  static constexpr double kCornerRel = 1e-8;

  EllipseDistanceCost(const Eigen::Vector2d& p, double t0) : p_(p), t_(t0) {}
  double latent_angle() const { return t_; }
  bool Evaluate(double const* const* x, double* r, double** jac) const override {
    const double* s = x[0];
    const Eigen::Vector2d c(s[0], s[1]);
    t_ = nearest_latent_angle_from(p_, c, s[2], s[3], s[4], t_);
    const Eigen::Matrix2d R = rotation(s[4]);
    const double ct = std::cos(t_), st = std::sin(t_);
    const Eigen::Vector2d e = c + R * Eigen::Vector2d(s[2] * ct, s[3] * st);
    Eigen::Vector2d nv = R * Eigen::Vector2d(s[3] * ct, s[2] * st);
    // A zero-width ellipse (b = 0, or b below rounding of a) has a corner at each tip. A point
    // beyond a tip is nearest to the corner, where the normal is undefined; the normal at an
    // angle a rounding away from the tip points across the axis, which made that point's
    // distance zero and stalled the fit at its start. Elsewhere p - e lies along the normal
    // of the nearest point, so there p - e is the direction.
    const Eigen::Vector2d d = p_ - e;
    const double dn = d.norm(), size = std::abs(s[2]) + std::abs(s[3]);
    if (nv.norm() < 1e-300 ||
        (dn > kCornerRel * size && std::abs(nv.dot(d)) < 0.5 * nv.norm() * dn))
      nv = d;
    const double nn = nv.norm();
    if (nn < 1e-300) {  // point exactly at such a tip: no direction, no residual
      r[0] = 0.0;
      if (jac && jac[0]) std::fill(jac[0], jac[0] + 5, 0.0);
      return true;
    }
    const Eigen::Vector2d nh = nv / nn;
    r[0] = nh.dot(d);
    if (jac && jac[0]) {
      const Eigen::Vector2d local(s[2] * ct, s[3] * st);
      const Eigen::Vector2d de_phi = R * Eigen::Vector2d(-local.y(), local.x());
      jac[0][0] = -nh.x();
      jac[0][1] = -nh.y();
      jac[0][2] = -nh.dot(R * Eigen::Vector2d(ct, 0.0));
      jac[0][3] = -nh.dot(R * Eigen::Vector2d(0.0, st));
      jac[0][4] = -nh.dot(de_phi);
    }
    return true;
  }

 private:
  Eigen::Vector2d p_;
  mutable double t_;
};

// Signed distance to the circle s = (cx, cy, r): closed form, no latent angle needed.
class CircleDistanceCost : public ceres::SizedCostFunction<1, 3> {
 public:
  explicit CircleDistanceCost(const Eigen::Vector2d& p) : p_(p) {}
  double latent_angle() const { return 0.0; }  // unused: the circle needs none
  bool Evaluate(double const* const* x, double* r, double** jac) const override {
    const double* s = x[0];
    const Eigen::Vector2d v = p_ - Eigen::Vector2d(s[0], s[1]);
    const double nv = v.norm();
    r[0] = nv - s[2];
    if (jac && jac[0]) {
      const Eigen::Vector2d u = nv > 0.0 ? Eigen::Vector2d(v / nv) : Eigen::Vector2d(1.0, 0.0);
      jac[0][0] = -u.x();
      jac[0][1] = -u.y();
      jac[0][2] = -1.0;
    }
    return true;
  }

 private:
  Eigen::Vector2d p_;
};

template <int kP>
struct DistanceCostOf;
template <>
struct DistanceCostOf<5> {
  using Type = EllipseDistanceCost;
  static Type* make(const Eigen::Vector2d& p, double t) { return new Type(p, t); }
};
template <>
struct DistanceCostOf<3> {
  using Type = CircleDistanceCost;
  static Type* make(const Eigen::Vector2d& p, double) { return new Type(p); }
};
template <int kP>
ceres::CostFunction* distance_cost(const Eigen::Vector2d& p, double t) {
  return DistanceCostOf<kP>::make(p, t);
}

// Classical 95%-efficiency tuning constants (in units of the noise sigma) for Gaussian data.
constexpr double kHuberK = 1.345;
constexpr double kCauchyK = 2.385;

std::unique_ptr<ceres::LossFunction> make_loss(FitLoss loss, double scale) {
  switch (loss) {
    case FitLoss::kHuber:
      return std::make_unique<ceres::HuberLoss>(scale);
    case FitLoss::kCauchy:
      return std::make_unique<ceres::CauchyLoss>(scale);
    default:
      return nullptr;
  }
}

double tuning_constant(FitLoss loss) { return loss == FitLoss::kHuber ? kHuberK : kCauchyK; }

template <class Residual, int kP>
CurveFit solve_once(const std::vector<Eigen::Vector2d>& q, std::vector<double> params,
                    std::vector<double> t, FitLoss loss, double loss_scale, bool covariance,
                    int max_iterations, FitMethod method) {
  CurveFit out;
  out.params = std::move(params);
  out.t = std::move(t);
  out.loss_scale = loss == FitLoss::kNone ? 0.0 : loss_scale;
  std::unique_ptr<ceres::LossFunction> loss_fn = make_loss(loss, loss_scale);
  ceres::Problem::Options popts;
  popts.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Solver::Options opts;
  opts.max_num_iterations = max_iterations;
  // Noiseless data must be recovered to near machine precision (tests ask 1e-8 relative).
  opts.function_tolerance = 1e-15;
  opts.gradient_tolerance = 1e-15;
  opts.parameter_tolerance = 1e-13;
  opts.logging_type = ceres::SILENT;
  opts.minimizer_progress_to_stdout = false;
  opts.num_threads = 1;
  ceres::Solver::Summary summary;
  if (method == FitMethod::kLatentAngles || kP == 3) {
    ceres::Problem problem(popts);
    for (std::size_t i = 0; i < q.size(); ++i) {
      auto* cost =
          new ceres::AutoDiffCostFunction<Residual, 2, kP, 1>(new Residual{q[i].x(), q[i].y()});
      problem.AddResidualBlock(cost, loss_fn.get(), out.params.data(), &out.t[i]);
    }
    // The latent angles form a block-diagonal part that the Schur complement eliminates
    // exactly: the reduced system is kP x kP whatever the number of points.
    opts.linear_solver_type = ceres::DENSE_SCHUR;
    ceres::Solve(opts, &problem, &summary);
  } else {
    // Variable projection: the latent angles are solved inside each residual evaluation, so
    // the solver sees kP unknowns only.
    ceres::Problem problem(popts);
    std::vector<const typename DistanceCostOf<kP>::Type*> costs;
    for (std::size_t i = 0; i < q.size(); ++i) {
      auto* cost = DistanceCostOf<kP>::make(q[i], out.t[i]);
      costs.push_back(cost);
      problem.AddResidualBlock(cost, loss_fn.get(), out.params.data());
    }
    opts.linear_solver_type = ceres::DENSE_QR;
    ceres::Solve(opts, &problem, &summary);
    // The costs hold the angles of the last evaluation, which may be a rejected trial step:
    // take the nearest points of the accepted solution.
    for (std::size_t i = 0; i < q.size(); ++i)
      out.t[i] = nearest_latent_angle_from(q[i], Eigen::Vector2d(out.params[0], out.params[1]),
                                           out.params[2], out.params[3], out.params[4],
                                           costs[i]->latent_angle());
  }
  out.converged = summary.termination_type == ceres::CONVERGENCE;
  out.iterations = static_cast<int>(summary.iterations.size());
  point_operations() += static_cast<std::int64_t>(q.size()) *
                        (summary.num_residual_evaluations + summary.num_jacobian_evaluations + 1);

  out.d.resize(q.size());
  for (std::size_t i = 0; i < q.size(); ++i) {
    double r[2];
    Residual{q[i].x(), q[i].y()}(out.params.data(), &out.t[i], r);
    out.d[i] = std::hypot(r[0], r[1]);
  }
  if (covariance) {
    point_operations() += static_cast<std::int64_t>(q.size());
    // The covariance is taken on the equivalent distance problem (5 or 3 parameters, see
    // EllipseDistanceCost) at the solution, with the same loss.
    ceres::Problem dproblem(popts);
    for (std::size_t i = 0; i < q.size(); ++i)
      dproblem.AddResidualBlock(distance_cost<kP>(q[i], out.t[i]), loss_fn.get(),
                                out.params.data());
    ceres::Covariance::Options copts;
    // Dense SVD with a pseudo-inverse: the one direction that can vanish is an exact
    // circle's inclination, which fit_ellipse detects and refits as a circle.
    copts.algorithm_type = ceres::DENSE_SVD;
    copts.null_space_rank = -1;
    copts.min_reciprocal_condition_number = 1e-14;
    copts.num_threads = 1;
    ceres::Covariance cov(copts);
    std::vector<std::pair<const double*, const double*>> blocks = {
        {out.params.data(), out.params.data()}};
    if (cov.Compute(blocks, &dproblem)) {
      Eigen::Matrix<double, kP, kP, Eigen::RowMajor> c;
      if (cov.GetCovarianceBlock(out.params.data(), out.params.data(), c.data())) {
        out.cov_unit = c;
        out.cov_ok = c.allFinite();
      }
    }
  }
  return out;
}

template <class Residual, int kP>
CurveFit solve_curve(const std::vector<Eigen::Vector2d>& q, std::vector<double> params,
                     std::vector<double> t, FitLoss loss, double loss_scale, bool covariance,
                     int max_iterations, FitMethod method, const std::vector<double>& d0) {
  const auto n = static_cast<double>(q.size());
  if (loss == FitLoss::kNone || loss_scale > 0.0) {
    CurveFit fit = solve_once<Residual, kP>(q, std::move(params), std::move(t), loss, loss_scale,
                                            covariance, max_iterations, method);
    if (loss == FitLoss::kNone) {
      double ssr = 0.0;
      for (double d : fit.d) ssr += d * d;
      fit.sigma = std::sqrt(ssr / std::max(1.0, n - kP));
    } else {
      fit.sigma =
          std::max(mad_scale(fit.d) * std::sqrt(n / std::max(1.0, n - kP)), kMinLossScale * 1e-3);
    }
    return fit;
  }
  // Automatic scale from the distances d0 to a high-breakdown start (robust_guess): pass 1
  // robust at k * MAD(d0); pass 2 rescaled from pass 1's residuals. A least-squares start
  // would not do: four outliers in 36 points can pull it so far that every residual, and
  // with them the MAD, is inflated and the loss no longer tells outliers from inliers.
  const double k = tuning_constant(loss);
  CurveFit fit;
  fit.params = std::move(params);
  fit.t = std::move(t);
  fit.d = d0;
  int iterations = 0;
  for (int pass = 1; pass <= 2; ++pass) {
    const double scale = std::max(kMinLossScale, k * mad_scale(fit.d));
    fit = solve_once<Residual, kP>(q, fit.params, fit.t, loss, scale, covariance && pass == 2,
                                   max_iterations, method);
    iterations += fit.iterations;
  }
  fit.iterations = iterations;
  // The robust fit's noise level: MAD of the residuals, rescaled for the n - p parameters
  // that the fit absorbed (the plain fit's sqrt(SSR / (n - p)) has the same correction).
  fit.sigma =
      std::max(mad_scale(fit.d) * std::sqrt(n / std::max(1.0, n - kP)), kMinLossScale * 1e-3);
  return fit;
}

}  // namespace

Normalized normalize(const std::vector<Eigen::Vector2d>& points) {
  Normalized out;
  if (points.empty()) return out;
  point_operations() += static_cast<std::int64_t>(points.size());
  // A power of two first brings the largest coordinate near 1, exactly (no rounding): the
  // sums of squares below would overflow for data near 1e300 and underflow near 1e-300.
  double largest = 0.0;
  for (const auto& p : points) largest = std::max({largest, std::abs(p.x()), std::abs(p.y())});
  if (!(largest > 0.0)) return out;  // all points at the origin: scale 0, degenerate
  // 2^(e-1) <= largest < 2^e: up = 2^(e-1) is finite for every finite largest (2^e was
  // infinite above 2^1023, about 9e307, and every number of the fit inf or nan).
  int e = 0;
  std::frexp(largest, &e);
  const double down = std::ldexp(1.0, 1 - e), up = std::ldexp(1.0, e - 1);
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (const auto& p : points) mean += p * down;
  mean /= static_cast<double>(points.size());
  double s2 = 0.0;
  for (const auto& p : points) s2 += (p * down - mean).squaredNorm();
  const double s = std::sqrt(s2 / static_cast<double>(points.size()));
  out.origin = mean * up;
  out.scale = s * up;
  if (!(s > 0.0)) return out;
  out.q.reserve(points.size());
  for (const auto& p : points) out.q.push_back((p * down - mean) / s);
  return out;
}

int count_distinct(const std::vector<Eigen::Vector2d>& q, double tol, int enough) {
  std::vector<Eigen::Vector2d> kept;
  for (const auto& p : q) {
    if (static_cast<int>(kept.size()) >= enough) break;
    bool seen = false;
    for (const auto& k : kept) {
      ++point_operations();
      if ((k - p).norm() <= tol) {
        seen = true;
        break;
      }
    }
    if (!seen) kept.push_back(p);
  }
  return static_cast<int>(kept.size());
}

double robust_cost(const std::vector<double>& d, FitLoss loss, double scale) {
  double sum = 0.0;
  const double c2 = scale * scale;
  for (double v : d) {
    const double s = v * v;
    if (loss == FitLoss::kHuber && scale > 0.0)
      sum += s <= c2 ? s : 2.0 * scale * std::sqrt(s) - c2;
    else if (loss == FitLoss::kCauchy && scale > 0.0)
      sum += c2 * std::log1p(s / c2);
    else
      sum += s;
  }
  return sum;
}

EllipseGuess best_guess(const std::vector<Eigen::Vector2d>& q, const std::vector<double>& theta,
                        bool use_theta, bool* used_theta) {
  *used_theta = false;
  if (use_theta && theta.size() == q.size()) {
    EllipseGuess g = ellipse_guess_from_affine(fit_detail::affine_fit(q, theta), theta);
    if (g.ok) {
      *used_theta = true;
      return g;
    }
  }
  EllipseGuess g = ellipse_guess_algebraic(q);
  if (g.ok) return g;
  // Principal axes: for points spread evenly in t, the variance along an axis of length a is
  // a^2 / 2. This always exists; fit_ellipse refuses collinear points (b = 0) without
  // directions before it fits.
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (const auto& p : q) mean += p;
  mean /= static_cast<double>(q.size());
  Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
  for (const auto& p : q) cov += (p - mean) * (p - mean).transpose();
  cov /= static_cast<double>(q.size());
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(cov);
  g.center = mean;
  g.a = std::sqrt(2.0 * std::max(0.0, es.eigenvalues()(1)));
  g.b = std::sqrt(2.0 * std::max(0.0, es.eigenvalues()(0)));
  const Eigen::Vector2d major = es.eigenvectors().col(1);
  g.phi = std::atan2(major.y(), major.x());
  g.t.clear();
  for (const auto& p : q) g.t.push_back(nearest_latent_angle(p, g.center, g.a, g.b, g.phi));
  g.ok = true;
  return g;
}

CurveFit solve_ellipse(const std::vector<Eigen::Vector2d>& q, const EllipseGuess& g, FitLoss loss,
                       double loss_scale, bool covariance, int max_iterations, FitMethod method) {
  std::vector<double> d0;
  if (loss != FitLoss::kNone && !(loss_scale > 0.0))
    for (const auto& p : q) d0.push_back(ellipse_distance(p, g.center, g.a, g.b, g.phi));
  return solve_curve<EllipsePointResidual, 5>(q, {g.center.x(), g.center.y(), g.a, g.b, g.phi}, g.t,
                                              loss, loss_scale, covariance, max_iterations, method,
                                              d0);
}

CurveFit solve_circle(const std::vector<Eigen::Vector2d>& q, const Eigen::Vector2d& c, double r,
                      const std::vector<double>& t, FitLoss loss, double loss_scale,
                      bool covariance, int max_iterations) {
  std::vector<double> d0;
  if (loss != FitLoss::kNone && !(loss_scale > 0.0))
    for (const auto& p : q) d0.push_back(std::abs((p - c).norm() - r));
  return solve_curve<CirclePointResidual, 3>(q, {c.x(), c.y(), r}, t, loss, loss_scale, covariance,
                                             max_iterations, FitMethod::kExactDistance, d0);
}

}  // namespace fit_detail

namespace {

using fit_detail::CurveFit;

void check_points(const Envelope& env, int min_points, const char* what) {
  std::string why;
  if (!env.IsValid(&why)) throw InputError(why);
  if (static_cast<int>(env.size()) < min_points)
    throw InputError(std::string("fit: ") + what + " needs at least " + std::to_string(min_points) +
                     " points, got " + std::to_string(env.size()));
}

// Residuals, rms and solver outcome of a curve fit, scaled back from normalized units by L;
// shared by the circle and ellipse results.
void fill_outcome(const CurveFit& f, double L, const FitOptions& options, bool used_theta,
                  EnvelopeFit* out) {
  double ssr = 0.0;  // in normalized units: finite for any finite data
  for (double d : f.d) {
    out->residuals.push_back(L * d);
    ssr += d * d;
  }
  out->rms = L * std::sqrt(ssr / static_cast<double>(f.d.size()));
  out->loss = options.loss;
  out->loss_scale = L * f.loss_scale;
  out->converged = f.converged;
  out->iterations = f.iterations;
  out->used_theta = used_theta;
}

// Fills the common members from a circle solution (normalized units -> data units).
EnvelopeFit circle_result(const fit_detail::Normalized& nz, const CurveFit& f,
                          const FitOptions& options, bool used_theta) {
  EnvelopeFit out;
  out.shape = FitShape::kCircle;
  out.n_points = static_cast<int>(nz.q.size());
  const double L = nz.scale;
  out.center = nz.origin + L * Eigen::Vector2d(f.params[0], f.params[1]);
  out.a = out.b = L * std::abs(f.params[2]);
  fill_outcome(f, L, options, used_theta, &out);
  if (f.cov_ok) {
    // Standard errors from the normalized covariance: finite where c3 itself overflows.
    const Eigen::Matrix3d cn = f.cov_unit * (f.sigma * f.sigma);
    const Eigen::Matrix3d c3 = cn * (L * L);
    out.has_stderr = true;
    out.center_stderr = L * Eigen::Vector2d(std::sqrt(cn(0, 0)), std::sqrt(cn(1, 1)));
    out.a_stderr = out.b_stderr = L * std::sqrt(cn(2, 2));
    out.covariance.topLeftCorner<3, 3>() = c3;
    out.covariance(3, 3) = c3(2, 2);
    out.covariance.block<3, 1>(0, 3) = c3.col(2);
    out.covariance.block<1, 3>(3, 0) = c3.row(2);
  }
  return out;
}

}  // namespace

namespace {
EnvelopeFit fit_ellipse_or_circle(const Envelope& env, const FitOptions& options);

// Points collinear to rounding (fit_detail::line_ssr) determine a line; `why` says what they
// leave undetermined for the shape asked for.
void refuse_collinear(const fit_detail::Normalized& nz, const std::string& why) {
  if (fit_detail::line_ssr(nz) > fit_detail::rounding_ssr(nz.q.size())) return;
  throw InputError("fit: the " + std::to_string(nz.q.size()) +
                   " points are collinear to rounding: " + why +
                   "; fit a line (shape line or auto)");
}
}  // namespace

EnvelopeFit fit_circle(const Envelope& env, const FitOptions& options) {
  const std::int64_t start = fit_detail::point_operations();
  check_points(env, 3, "a circle");
  const fit_detail::Normalized nz = fit_detail::normalize(env.response);
  if (!(nz.scale > 0.0)) throw InputError("fit: degenerate data, all points coincide");
  refuse_collinear(nz, "a circle through them would have an infinite radius");
  // Kasa's linear fit x^2 + y^2 + D x + E y + F = 0 as the start.
  const auto n = static_cast<Eigen::Index>(nz.q.size());
  Eigen::MatrixXd X(n, 3);
  Eigen::VectorXd y(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const auto& p = nz.q[static_cast<std::size_t>(i)];
    X.row(i) << p.x(), p.y(), 1.0;
    y(i) = -p.squaredNorm();
  }
  const Eigen::Vector3d s = X.colPivHouseholderQr().solve(y);
  Eigen::Vector2d c(-s(0) / 2.0, -s(1) / 2.0);
  double r2 = c.squaredNorm() - s(2);
  if (!c.allFinite() || !(r2 > 0.0)) c.setZero(), r2 = 1.0;
  std::vector<double> t;
  for (const auto& p : nz.q) t.push_back(std::atan2(p.y() - c.y(), p.x() - c.x()));
  const double scale = options.loss_scale > 0.0 ? options.loss_scale / nz.scale : 0.0;
  const CurveFit f = fit_detail::solve_circle(nz.q, c, std::sqrt(r2), t, options.loss, scale,
                                              options.compute_covariance, options.max_iterations);
  EnvelopeFit out = circle_result(nz, f, options, false);
  out.selection_note = "circle requested";
  out.point_operations = fit_detail::point_operations() - start;
  return out;
}

EnvelopeFit fit_ellipse(const Envelope& env, const FitOptions& options) {
  const std::int64_t start = fit_detail::point_operations();
  EnvelopeFit f = fit_ellipse_or_circle(env, options);
  f.point_operations = fit_detail::point_operations() - start;
  return f;
}

namespace {

EnvelopeFit fit_ellipse_or_circle(const Envelope& env, const FitOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) throw InputError(why);
  check_points(env, 5, "an ellipse");
  const fit_detail::Normalized nz = fit_detail::normalize(env.response);
  if (!(nz.scale > 0.0)) throw InputError("fit: degenerate data, all points coincide");
  // Five distinct points determine a conic; duplicates carry no shape information.
  constexpr double kDistinctTol = 1e-9;
  if (fit_detail::count_distinct(nz.q, kDistinctTol, 5) < 5)
    throw InputError("fit: an ellipse needs at least 5 distinct points");
  bool used_theta = false;
  const EllipseGuess g =
      options.loss == FitLoss::kNone
          ? fit_detail::best_guess(nz.q, env.theta_deg, options.use_theta, &used_theta)
          : fit_detail::robust_guess(nz.q, env.theta_deg, options.use_theta, options.seed,
                                     &used_theta);
  // Every segment that covers collinear points fits them exactly: only the directions (a
  // rank-one map) say which. Without them the fit stalled at its start and reported a wrong
  // segment (b = 0, a from the points' spread) as converged.
  if (!used_theta)
    refuse_collinear(nz,
                     "without the probe directions (theta_deg) no ellipse through them is "
                     "determined");
  const double scale = options.loss_scale > 0.0 ? options.loss_scale / nz.scale : 0.0;
  CurveFit f = fit_detail::solve_ellipse(nz.q, g, options.loss, scale, options.compute_covariance,
                                         options.max_iterations, options.method);
  const double L = nz.scale;

  // Fold to a >= b >= 0, phi in [0, pi). F maps the raw (cx, cy, a, b, phi) covariance.
  double a = f.params[2], b = f.params[3], phi = f.params[4];
  Eigen::Matrix<double, 5, 5> F = Eigen::Matrix<double, 5, 5>::Identity();
  if (a < 0.0) a = -a, F(2, 2) = -1.0;
  if (b < 0.0) b = -b, F(3, 3) = -1.0;
  if (b > a) {
    std::swap(a, b);
    F.row(2).swap(F.row(3));
    phi += kPi / 2.0;
  }
  phi = fit_detail::fold_pi(phi);

  EnvelopeFit out;
  out.shape = FitShape::kEllipse;
  out.n_points = static_cast<int>(env.size());
  out.center = nz.origin + L * Eigen::Vector2d(f.params[0], f.params[1]);
  out.a = L * a;
  out.b = L * b;
  out.inclination_deg = rad_to_deg(phi);
  fill_outcome(f, L, options, used_theta, &out);
  out.selection_note = "ellipse requested";

  // A circle has no inclination: a - b within circle_z standard errors (or exactly equal to
  // 1e-9 relative, the noiseless case) is refitted as a circle.
  constexpr double kCircleRelTol = 1e-9;
  bool circle = (a - b) <= kCircleRelTol * a;
  if (f.cov_ok) {
    // Judged and turned into standard errors in normalized units (Cn), then scaled by L:
    // finite for data near 1e300 even where the covariance itself overflows.
    const Eigen::Matrix<double, 5, 5> Cn = F * f.cov_unit * F.transpose() * (f.sigma * f.sigma);
    Eigen::Matrix<double, 5, 5> D = Eigen::Matrix<double, 5, 5>::Identity();
    D.diagonal() << L, L, L, L, 1.0;
    const double var_diff = Cn(2, 2) + Cn(3, 3) - 2.0 * Cn(2, 3);
    if (var_diff > 0.0 && a - b <= options.circle_z * std::sqrt(var_diff)) circle = true;
    out.covariance = D * Cn * D;
    out.has_stderr = Cn.diagonal().minCoeff() >= 0.0;
    if (out.has_stderr) {
      out.center_stderr = L * Eigen::Vector2d(std::sqrt(Cn(0, 0)), std::sqrt(Cn(1, 1)));
      out.a_stderr = L * std::sqrt(Cn(2, 2));
      out.b_stderr = L * std::sqrt(Cn(3, 3));
      out.inclination_stderr_deg = rad_to_deg(std::sqrt(Cn(4, 4)));
    }
  }
  if (circle) {
    std::vector<double> t;
    for (const auto& p : nz.q) t.push_back(std::atan2(p.y() - f.params[1], p.x() - f.params[0]));
    const CurveFit fc = fit_detail::solve_circle(
        nz.q, Eigen::Vector2d(f.params[0], f.params[1]), 0.5 * (a + b), t, options.loss, scale,
        options.compute_covariance, options.max_iterations);
    EnvelopeFit c = circle_result(nz, fc, options, used_theta);
    c.selection_note = "ellipse requested; axes equal within " + decimal_g(options.circle_z) +
                       " standard errors: circle, inclination undefined";
    return c;
  }
  return out;
}

}  // namespace

}  // namespace rendulic

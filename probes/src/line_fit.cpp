// Line fit of an envelope (docs/physics.md section 6: the line is the degenerate ellipse b = 0;
// docs/fitting.md "Method"). Direction and offset by total least squares (principal axis of the
// scatter), iteratively reweighted for the robust losses. The segment's centre and half
// length a (the envelope's extent, hence its directional stiffness) come from the probe
// directions when known (the along-line coordinate regressed on cos, sin theta, exact for a
// rank-one linear law), else from the extreme projections.
#include <algorithm>
#include <cmath>

#include "fit_internal.hpp"
#include "rendulic/core/conventions.hpp"
#include "rendulic/core/errors.hpp"
#include "rendulic/probes/envelope_fit.hpp"

namespace rendulic {
namespace {

constexpr double kHuberK = 1.345;
constexpr double kCauchyK = 2.385;
constexpr int kIrlsIterations = 30;

}  // namespace

namespace fit_detail {

Tls weighted_tls(const std::vector<Eigen::Vector2d>& q, const std::vector<double>& w) {
  point_operations() += static_cast<std::int64_t>(q.size());
  Tls out;
  double wsum = 0.0;
  out.centroid.setZero();
  for (std::size_t i = 0; i < q.size(); ++i) out.centroid += w[i] * q[i], wsum += w[i];
  out.centroid /= wsum;
  Eigen::Matrix2d S = Eigen::Matrix2d::Zero();
  for (std::size_t i = 0; i < q.size(); ++i)
    S += w[i] * (q[i] - out.centroid) * (q[i] - out.centroid).transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(S);
  out.d = es.eigenvectors().col(1);
  out.nrm = Eigen::Vector2d(-out.d.y(), out.d.x());
  for (const auto& p : q) {
    out.s.push_back(out.d.dot(p - out.centroid));
    out.h.push_back(out.nrm.dot(p - out.centroid));
  }
  return out;
}

double line_ssr(const Normalized& nz) {
  double ssr = 0.0;
  for (double h : weighted_tls(nz.q, std::vector<double>(nz.q.size(), 1.0)).h) ssr += h * h;
  return ssr;
}

}  // namespace fit_detail

EnvelopeFit fit_line(const Envelope& env, const FitOptions& options) {
  const std::int64_t start = fit_detail::point_operations();
  std::string why;
  if (!options.IsValid(&why)) throw InputError(why);
  if (!env.IsValid(&why)) throw InputError(why);
  if (env.size() < 2)
    throw InputError("fit: a line needs at least 2 points, got " + std::to_string(env.size()));
  const fit_detail::Normalized nz = fit_detail::normalize(env.response);
  if (!(nz.scale > 0.0)) throw InputError("fit: degenerate data, all points coincide");
  const std::vector<Eigen::Vector2d>& q = nz.q;
  const std::size_t n = q.size();

  std::vector<double> w(n, 1.0);
  fit_detail::Tls tls = fit_detail::weighted_tls(q, w);
  double loss_scale = 0.0;
  if (options.loss != FitLoss::kNone) {
    const double k = options.loss == FitLoss::kHuber ? kHuberK : kCauchyK;
    for (int it = 0; it < kIrlsIterations; ++it) {
      loss_scale = options.loss_scale > 0.0
                       ? options.loss_scale / nz.scale
                       : std::max(fit_detail::kMinLossScale, k * fit_detail::mad_scale(tls.h));
      for (std::size_t i = 0; i < n; ++i) {
        const double u = std::abs(tls.h[i]) / loss_scale;
        w[i] = options.loss == FitLoss::kHuber ? (u <= 1.0 ? 1.0 : 1.0 / u) : 1.0 / (1.0 + u * u);
      }
      const fit_detail::Tls next = fit_detail::weighted_tls(q, w);
      const bool done =
          (next.centroid - tls.centroid).norm() < 1e-14 && std::abs(next.d.dot(tls.nrm)) < 1e-14;
      tls = next;
      if (done) break;
    }
  }
  // Points that count as inliers for the extent: all, or those the robust loss keeps at
  // half weight or more.
  std::vector<std::size_t> in;
  for (std::size_t i = 0; i < n; ++i)
    if (w[i] >= 0.5) in.push_back(i);
  if (in.size() < 2) {  // the loss discounts (almost) everything: no basis for a choice
    in.clear();
    for (std::size_t i = 0; i < n; ++i) in.push_back(i);
  }

  double wsum = 0.0, whh = 0.0;
  for (std::size_t i = 0; i < n; ++i) wsum += w[i], whh += w[i] * tls.h[i] * tls.h[i];
  // Noise across the line; n - 2 for the direction and offset.
  const double dof = std::max(1.0, static_cast<double>(in.size()) - 2.0);
  const double sigma = options.loss == FitLoss::kNone
                           ? std::sqrt(whh / dof)
                           : fit_detail::mad_scale(tls.h) * std::sqrt(static_cast<double>(n) / dof);

  // Along-line centre s0 and half-length a.
  double s0 = 0.0, a = 0.0, var_s0 = 0.0, var_a = 0.0;
  bool used_theta = false;
  if (options.use_theta && env.has_theta() && in.size() >= 4) {
    const auto m = static_cast<Eigen::Index>(in.size());
    Eigen::MatrixXd X(m, 3);
    Eigen::VectorXd y(m);
    for (Eigen::Index k = 0; k < m; ++k) {
      const std::size_t i = in[static_cast<std::size_t>(k)];
      const double t = deg_to_rad(env.theta_deg[i]);
      X.row(k) << 1.0, std::cos(t), std::sin(t);
      y(k) = tls.s[i];
    }
    Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(X);
    if (qr.rank() == 3) {
      const Eigen::Vector3d beta = qr.solve(y);
      const double var_e = (X * beta - y).squaredNorm() / static_cast<double>(m - 3);
      const Eigen::Matrix3d cb = var_e * (X.transpose() * X).inverse();
      s0 = beta(0);
      a = beta.tail<2>().norm();
      var_s0 = cb(0, 0);
      if (a > 0.0) {
        const Eigen::Vector2d g = beta.tail<2>() / a;
        var_a = g.dot(cb.bottomRightCorner<2, 2>() * g);
      }
      used_theta = true;
    }
  }
  if (!used_theta) {
    double lo = tls.s[in.front()], hi = lo;
    for (std::size_t i : in) lo = std::min(lo, tls.s[i]), hi = std::max(hi, tls.s[i]);
    s0 = 0.5 * (lo + hi);
    a = 0.5 * (hi - lo);
    // Extremes carry the along-line noise of one point each; with isotropic noise sigma that
    // is var(a) = var(s0) = sigma^2 / 2 (an approximation, not a covariance: docs/fitting.md).
    var_s0 = var_a = 0.5 * sigma * sigma;
  }

  double sdd = 0.0, s_mean = 0.0;
  for (std::size_t i : in) s_mean += tls.s[i];
  s_mean /= static_cast<double>(in.size());
  for (std::size_t i : in) sdd += (tls.s[i] - s_mean) * (tls.s[i] - s_mean);
  if (!(sdd > 0.0)) throw InputError("fit: degenerate data, fewer than 2 distinct points");

  const double L = nz.scale;
  EnvelopeFit out;
  out.shape = FitShape::kLine;
  out.n_points = static_cast<int>(n);
  out.center = nz.origin + L * (tls.centroid + s0 * tls.d);
  out.a = L * a;
  out.b = 0.0;
  const double phi = fit_detail::fold_pi(std::atan2(tls.d.y(), tls.d.x()));
  out.inclination_deg = rad_to_deg(phi);
  double ssr = 0.0;  // in normalized units: finite for any finite data
  for (double h : tls.h) out.residuals.push_back(L * std::abs(h)), ssr += h * h;
  out.rms = L * std::sqrt(ssr / static_cast<double>(n));
  out.loss = options.loss;
  out.loss_scale = L * loss_scale;
  out.converged = true;
  out.used_theta = used_theta;
  out.selection_note = "line requested";
  if (options.compute_covariance && in.size() >= 3) {
    // Total least squares to first order: var(direction) = sigma^2 / sum (s - s_mean)^2,
    // the offset at the centroid sigma^2 / n; the centre, s0 away from the centroid, also
    // moves across the line when the direction turns.
    const double var_phi = sigma * sigma / sdd;
    const double var_off = sigma * sigma / static_cast<double>(in.size());
    const double var_across = var_off + s0 * s0 * var_phi;
    Eigen::Matrix2d B;
    B.col(0) = tls.d;
    B.col(1) = tls.nrm;
    // In normalized units first (Cn), then scaled by L: the standard errors stay finite for
    // data near 1e300 even where the covariance itself overflows.
    const Eigen::Matrix2d cc = B * Eigen::Vector2d(var_s0, var_across).asDiagonal() * B.transpose();
    Eigen::Matrix<double, 5, 5> Cn = Eigen::Matrix<double, 5, 5>::Zero();
    Cn.topLeftCorner<2, 2>() = cc;
    Cn(2, 2) = var_a;
    Cn(4, 4) = var_phi;
    const Eigen::Vector2d c_phi = tls.nrm * (s0 * var_phi);
    Cn.block<2, 1>(0, 4) = c_phi;
    Cn.block<1, 2>(4, 0) = c_phi.transpose();
    Eigen::Matrix<double, 5, 5> D = Eigen::Matrix<double, 5, 5>::Identity();
    D.diagonal() << L, L, L, L, 1.0;
    out.covariance = D * Cn * D;
    out.has_stderr = true;
    out.center_stderr = L * Eigen::Vector2d(std::sqrt(Cn(0, 0)), std::sqrt(Cn(1, 1)));
    out.a_stderr = L * std::sqrt(Cn(2, 2));
    out.b_stderr = 0.0;
    out.inclination_stderr_deg = rad_to_deg(std::sqrt(var_phi));
  }
  out.point_operations = fit_detail::point_operations() - start;
  return out;
}

}  // namespace rendulic

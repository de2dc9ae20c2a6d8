// Envelope features (docs/physics.md section 6); see features.hpp. Errors are
// first-order propagations of the fits' covariances (delta method).
#include "rendulic/probes/features.hpp"

#include <cmath>

#include "rendulic/core/affine_map.hpp"
#include "rendulic/core/conventions.hpp"
#include "rendulic/core/errors.hpp"

namespace rendulic {
namespace {

void check_amplitude(double amplitude, const char* what) {
  if (!(amplitude > 0.0) || !std::isfinite(amplitude))
    throw InputError(std::string("features: ") + what + " must be finite and > 0");
}

double var_ratio(double x, double vx, double y, double vy, double cxy) {
  // var(x / y) to first order.
  const double r = x / y;
  return (vx - 2.0 * r * cxy + r * r * vy) / (y * y);
}

}  // namespace

EnvelopeFeatures envelope_features(const EnvelopeFit& fit, double amplitude) {
  check_amplitude(amplitude, "amplitude");
  EnvelopeFeatures f;
  const Eigen::Matrix<double, 5, 5>& C = fit.covariance;
  f.amplitude = amplitude;
  f.stiffness_major = fit.a / amplitude;
  f.stiffness_minor = fit.b / amplitude;
  f.aspect_ratio = fit.a > 0.0 ? fit.b / fit.a : 0.0;
  f.inclination_deg = fit.inclination_deg;
  f.inclination_stderr_deg = fit.inclination_stderr_deg;
  f.center = fit.center;
  f.center_iso_dev = iso_dev_from_rendulic(fit.center);
  f.center_shift = fit.center.norm();
  f.center_shift_relative = fit.a > 0.0 ? f.center_shift / fit.a : 0.0;
  f.has_stderr = fit.has_stderr;
  if (fit.has_stderr) {
    f.stiffness_major_stderr = fit.a_stderr / amplitude;
    f.stiffness_minor_stderr = fit.b_stderr / amplitude;
    if (fit.a > 0.0)
      f.aspect_ratio_stderr =
          std::sqrt(std::max(0.0, var_ratio(fit.b, C(3, 3), fit.a, C(2, 2), C(2, 3))));
    // |c|: gradient c / |c|; at c = 0 the first-order error is undefined, and the honest
    // scale is the centre's own error (the norm of a zero-mean 2D Gaussian).
    double var_shift;
    Eigen::Vector2d g = Eigen::Vector2d::Zero();
    if (f.center_shift > 0.0) {
      g = fit.center / f.center_shift;
      var_shift = g.dot(C.topLeftCorner<2, 2>() * g);
    } else {
      var_shift = C(0, 0) + C(1, 1);
    }
    f.center_shift_stderr = std::sqrt(std::max(0.0, var_shift));
    if (fit.a > 0.0) {
      const double cov_sa = g.dot(C.block<2, 1>(0, 2));
      f.center_shift_relative_stderr =
          std::sqrt(std::max(0.0, var_ratio(f.center_shift, var_shift, fit.a, C(2, 2), cov_sa)));
    }
  }
  return f;
}

RendulicStiffness fit_rendulic_stiffness(const Envelope& env) {
  std::string why;
  if (!env.IsValid(&why)) throw InputError(why);
  const std::vector<Eigen::Vector2d> e = env.strain_points();
  if (e.empty())
    throw InputError(
        "stiffness: the envelope has no strain points (strain, or theta_deg "
        "with an amplitude)");
  const auto n = static_cast<Eigen::Index>(env.size());
  if (n < 3) throw InputError("stiffness: needs at least 3 probes");
  // Unknowns (c1, c2, D11, D12, D22); each probe gives two rows.
  Eigen::MatrixXd X = Eigen::MatrixXd::Zero(2 * n, 5);
  Eigen::VectorXd y(2 * n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const auto& ei = e[static_cast<std::size_t>(i)];
    const auto& ri = env.response[static_cast<std::size_t>(i)];
    X.row(2 * i) << 1.0, 0.0, ei.x(), ei.y(), 0.0;
    X.row(2 * i + 1) << 0.0, 1.0, 0.0, ei.x(), ei.y();
    y(2 * i) = ri.x();
    y(2 * i + 1) = ri.y();
  }
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(X);
  const AffineMapFit affine = fit_affine_map(e, env.response);
  if (qr.rank() < 5 || affine.rank < 3)
    throw InputError("stiffness: the strain points span fewer than 3 independent directions");
  const Eigen::VectorXd beta = qr.solve(y);
  RendulicStiffness out;
  out.center = beta.head<2>();
  out.D << beta(2), beta(3), beta(3), beta(4);
  const double ssr = (X * beta - y).squaredNorm();
  out.rms = std::sqrt(ssr / static_cast<double>(n));
  const double dof = std::max(1.0, 2.0 * static_cast<double>(n) - 5.0);
  const Eigen::MatrixXd cov = (ssr / dof) * (X.transpose() * X).inverse();
  out.center_stderr = cov.diagonal().head<2>().cwiseMax(0.0).cwiseSqrt();
  out.D_stderr = cov.diagonal().tail<3>().cwiseMax(0.0).cwiseSqrt();
  out.M = affine.map;
  const double mn = out.M.norm();
  out.asymmetry = mn > 0.0 ? (out.M - out.M.transpose()).norm() / (2.0 * mn) : 0.0;
  return out;
}

ElasticPlasticComparison compare_elastic_plastic(const EnvelopeFit& el, double amp_el,
                                                 const EnvelopeFit& pl, double amp_pl) {
  check_amplitude(amp_el, "elastic amplitude");
  check_amplitude(amp_pl, "plastic amplitude");
  if (!(el.a > 0.0) || !(pl.a > 0.0))
    throw InputError("features: an envelope of zero size cannot be compared");
  ElasticPlasticComparison out;
  const Eigen::Matrix<double, 5, 5>& Ce = el.covariance;
  const Eigen::Matrix<double, 5, 5>& Cp = pl.covariance;
  out.shift = pl.center / amp_pl - el.center / amp_el;
  out.shift_norm = out.shift.norm();
  const Eigen::Matrix2d cs =
      Cp.topLeftCorner<2, 2>() / (amp_pl * amp_pl) + Ce.topLeftCorner<2, 2>() / (amp_el * amp_el);
  out.shift_norm_stderr = std::sqrt(std::max(
      0.0, out.shift_norm > 0.0 ? (out.shift / out.shift_norm).dot(cs * out.shift / out.shift_norm)
                                : cs.trace()));
  out.shift_relative = out.shift_norm / (pl.a / amp_pl);

  // Ratios of independent quantities: relative variances add.
  const double ka_e = el.a / amp_el, ka_p = pl.a / amp_pl;
  out.major_ratio = ka_p / ka_e;
  out.major_ratio_stderr =
      out.major_ratio * std::sqrt(Cp(2, 2) / (pl.a * pl.a) + Ce(2, 2) / (el.a * el.a));
  if (el.b > 0.0) {
    const double mr = (pl.b / amp_pl) / (el.b / amp_el);
    out.minor_ratio = mr;
    out.minor_ratio_stderr =
        pl.b > 0.0          ? mr * std::sqrt(Cp(3, 3) / (pl.b * pl.b) + Ce(3, 3) / (el.b * el.b))
        : el.b_stderr > 0.0 ? std::sqrt(Cp(3, 3)) / amp_pl / (el.b / amp_el)
                            : 0.0;
    const double re = el.b / el.a, rp = pl.b / pl.a;
    out.thinning = rp / re;
    const double vre = var_ratio(el.b, Ce(3, 3), el.a, Ce(2, 2), Ce(2, 3));
    const double vrp = var_ratio(pl.b, Cp(3, 3), pl.a, Cp(2, 2), Cp(2, 3));
    out.thinning_stderr =
        std::sqrt(std::max(0.0, vrp / (re * re) + rp * rp * vre / (re * re * re * re)));
  }
  if (el.inclination_deg && pl.inclination_deg) {
    double d = *pl.inclination_deg - *el.inclination_deg;  // axes: modulo 180
    while (d > 90.0) d -= 180.0;
    while (d <= -90.0) d += 180.0;
    out.rotation_deg = d;
    if (el.inclination_stderr_deg && pl.inclination_stderr_deg)
      out.rotation_stderr_deg = std::hypot(*el.inclination_stderr_deg, *pl.inclination_stderr_deg);
  }
  return out;
}

}  // namespace rendulic

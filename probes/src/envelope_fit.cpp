// Shape selection of the envelope fit: line or ellipse, then the circle flag
// (in fit_ellipse). The criterion, stated in docs/fitting.md:
// - With the probe directions: an F-test. For an envelope c + M u(theta), the distance of a
//   point from the best line is n . M u(theta) (n the line's normal), a combination of
//   cos theta and sin theta that vanishes exactly when the envelope is a line (rank-one M).
//   Regressing the signed line residuals on (cos theta, sin theta) gives
//   F = (drop in SSR / 2) / (SSR / (m - 4)) ~ F(2, m - 4) under the line with Gaussian noise.
// - Without them: a parametric-bootstrap likelihood-ratio test. The orthogonal-distance
//   ellipse is not a regular nesting of the line there: it can put each noisy point of a
//   line on the nearer of its two sides and cut the squared residuals by about 60% with
//   b ~ 0.8 sigma, so a textbook F(1, n - 5) would call almost every noisy line an ellipse.
//   The bootstrap draws the distribution of T = cost(line) / cost(ellipse) under the fitted
//   line itself (same projections, Gaussian noise of the line's residual level) with the
//   very fitting procedure used on the data, so the test has its stated size.
// - Either way, an ellipse whose semi-major axis exceeds kMaxAxisOverSize times the points'
//   rms radius is not what the points support: probes all around the circle of directions
//   span their own envelope (a/rms = sqrt(2) for a thin one), so such a fit has run away
//   along a nearly straight cloud the test found not quite straight (noise with structure).
//   The line stands then, and the note says so.
#include <algorithm>
#include <cmath>
#include <optional>
#include <random>
#include <sstream>
#include <vector>

#include "fit_internal.hpp"
#include "rendulic/core/conventions.hpp"
#include "rendulic/core/decimal.hpp"
#include "rendulic/core/envelope_record.hpp"
#include "rendulic/core/errors.hpp"

namespace rendulic {

std::string to_string(FitShape shape) {
  switch (shape) {
    case FitShape::kEllipse:
      return "ellipse";
    case FitShape::kLine:
      return "line";
    case FitShape::kCircle:
      return "circle";
    case FitShape::kAuto:
      return "auto";
  }
  return "?";
}

std::string to_string(FitLoss loss) {
  switch (loss) {
    case FitLoss::kNone:
      return "none";
    case FitLoss::kHuber:
      return "huber";
    case FitLoss::kCauchy:
      return "cauchy";
  }
  return "?";
}

FitShape fit_shape_from_string(const std::string& name) {
  for (FitShape s : {FitShape::kEllipse, FitShape::kLine, FitShape::kCircle, FitShape::kAuto})
    if (to_string(s) == name) return s;
  throw InputError("fit: unknown shape '" + name + "' (ellipse, line, circle, auto)");
}

FitLoss fit_loss_from_string(const std::string& name) {
  for (FitLoss l : {FitLoss::kNone, FitLoss::kHuber, FitLoss::kCauchy})
    if (to_string(l) == name) return l;
  throw InputError("fit: unknown loss '" + name + "' (none, huber, cauchy)");
}

const std::vector<std::string>& fit_shape_choices() {
  static const std::vector<std::string> names{
      to_string(FitShape::kAuto), to_string(FitShape::kEllipse), to_string(FitShape::kLine)};
  return names;
}

const std::vector<std::string>& fit_loss_choices() {
  static const std::vector<std::string> names{to_string(FitLoss::kNone), to_string(FitLoss::kHuber),
                                              to_string(FitLoss::kCauchy)};
  return names;
}

bool FitOptions::IsValid(std::string* why) const {
  auto fail = [why](const char* msg) {
    if (why) *why = msg;
    return false;
  };
  if (!(loss_scale >= 0.0) || !std::isfinite(loss_scale))
    return fail("fit: loss_scale must be finite and >= 0 (0: automatic)");
  if (!(selection_alpha > 0.0 && selection_alpha < 1.0))
    return fail("fit: selection_alpha must lie in (0, 1)");
  if (bootstrap_samples < 19 || bootstrap_samples > 100000)
    return fail("fit: bootstrap_samples must lie in [19, 100000]");
  if (!(circle_z >= 0.0) || !std::isfinite(circle_z))
    return fail("fit: circle_z must be finite and >= 0");
  if (max_iterations < 1) return fail("fit: max_iterations must be >= 1");
  return true;
}

namespace {

// The largest semi-major axis of a selected ellipse, in rms radii of its points (see top).
constexpr double kMaxAxisOverSize = 4.0;

// Cost of a fit at the ellipse's loss scale: both shapes are judged by the same rho. In units
// of `unit` (the data's size): only ratios of costs are used, and squares of data near 1e300
// would overflow.
double cost_of(const EnvelopeFit& f, FitLoss loss, double scale, double unit) {
  std::vector<double> r;
  r.reserve(f.residuals.size());
  for (double d : f.residuals) r.push_back(d / unit);
  return fit_detail::robust_cost(r, loss, scale / unit);
}

double sum_of_squares(const std::vector<double>& residuals, double unit) {
  double ssr = 0.0;
  for (double r : residuals) ssr += (r / unit) * (r / unit);
  return ssr;
}

EnvelopeFit select_shape(const Envelope& env, const FitOptions& options);

}  // namespace

EnvelopeFit fit_envelope(const Envelope& env, const FitOptions& options) {
  const std::int64_t start = fit_detail::point_operations();
  EnvelopeFit f = select_shape(env, options);
  f.point_operations = fit_detail::point_operations() - start;
  // Points near the largest double can make a number beyond it (a line's half-length along a
  // diagonal), printed as inf, or null in JSON, with exit 0. (The covariance, which no file
  // stores, holds squares: beyond about 1e154 it overflows where the standard errors do not.)
  const bool finite = f.center.allFinite() && std::isfinite(f.a) && std::isfinite(f.b) &&
                      std::isfinite(f.inclination_deg.value_or(0.0)) && std::isfinite(f.rms) &&
                      f.center_stderr.allFinite() && std::isfinite(f.a_stderr) &&
                      std::isfinite(f.b_stderr) &&
                      std::isfinite(f.inclination_stderr_deg.value_or(0.0));
  if (!finite) {
    double largest = 0.0;
    for (const auto& p : env.response) largest = std::max(largest, p.cwiseAbs().maxCoeff());
    throw InputError("fit: the fit's numbers exceed the largest double (the points reach " +
                     decimal_g(largest) + "); rescale the points");
  }
  return f;
}

namespace {

// Refuses points whose sizes span more than the fit can resolve (kMaxEnvelopeSpan,
// envelope_record.hpp): a damaged point, in practice, named with the median it dwarfs.
void refuse_beyond_span(const std::vector<Eigen::Vector2d>& points) {
  const std::optional<SpanExcess> x = span_excess(points);
  if (!x) return;
  throw InputError("fit: response point " + std::to_string(x->index) + " reaches " +
                   decimal_g(x->size) + ", more than " + decimal_g(kMaxEnvelopeSpan) +
                   " times the median point's " + decimal_g(x->median) +
                   ": the fit cannot resolve the others beside it (a damaged point?)");
}

EnvelopeFit select_shape(const Envelope& env, const FitOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) throw InputError(why);
  if (!env.IsValid(&why)) throw InputError(why);
  refuse_beyond_span(env.response);
  // A given scale is in data units: 1e308 went into the fit as inf, 1e-320 failed it and the
  // message blamed the data.
  if (options.loss != FitLoss::kNone && options.loss_scale > 0.0) {
    const double size = fit_detail::normalize(env.response).scale;
    const double ratio = options.loss_scale / size;
    if (size > 0.0 && !(ratio >= fit_detail::kMinLossScale && ratio <= fit_detail::kMaxLossScale)) {
      std::ostringstream msg;
      msg << "fit: loss_scale " << options.loss_scale << " is " << ratio
          << " times the data's size " << size << "; give one within " << fit_detail::kMinLossScale
          << " to " << fit_detail::kMaxLossScale << " times it (0: automatic)";
      throw InputError(msg.str());
    }
  }
  switch (options.shape) {
    case FitShape::kEllipse:
      return fit_ellipse(env, options);
    case FitShape::kLine:
      return fit_line(env, options);
    case FitShape::kCircle:
      return fit_circle(env, options);
    case FitShape::kAuto:
      break;
  }
  // The hint only where a line can be fitted (2 points): with 0 or 1 it failed again.
  if (env.size() < 5)
    throw InputError("fit: choosing between ellipse and line needs at least 5 points, got " +
                     std::to_string(env.size()) + (env.size() >= 2 ? " (use --shape line)" : ""));
  EnvelopeFit line = fit_line(env, options);
  // A line fits exactly (to rounding): nothing left for an ellipse to explain. This also
  // spares fit_ellipse the points of a zero-width curve.
  // Sums of squares in units of the data's size L (nz.scale): scale-free, and finite for any
  // finite data.
  const fit_detail::Normalized nz = fit_detail::normalize(env.response);
  const double L = nz.scale;
  const double n = static_cast<double>(env.size());
  const double tiny = fit_detail::rounding_ssr(env.size());
  const double ssr_line = sum_of_squares(line.residuals, L);
  if (ssr_line <= tiny) {
    line.selection_note = "auto: line (points collinear to rounding)";
    return line;
  }
  const double phi = deg_to_rad(*line.inclination_deg);
  const Eigen::Vector2d d(std::cos(phi), std::sin(phi)), nrm(-d.y(), d.x());
  std::ostringstream note;
  // The ellipse is fitted only when needed: on a noisy line, with the directions, it can
  // wander off towards a -> infinity for its full iteration budget.
  std::optional<EnvelopeFit> ell;
  auto choose = [&](double p, const std::string& how) -> EnvelopeFit {
    if (p < options.selection_alpha) {
      if (!ell) ell = fit_ellipse(env, options);
      if (ell->a > kMaxAxisOverSize * L) {
        note << "auto: line (the line is rejected by " << how << ": p = " << p << " < "
             << options.selection_alpha << ", but the ellipse fit runs away: semi-major axis "
             << ell->a / L << " x the points' rms radius, beyond " << kMaxAxisOverSize << ")";
        line.line_p_value = p;
        line.selection_note = note.str();
        return line;
      }
      note << "auto: " << to_string(ell->shape) << " (line rejected by " << how << ": p = " << p
           << " < " << options.selection_alpha << ")";
      if (ell->shape == FitShape::kCircle) note << "; axes equal within the errors";
      ell->line_p_value = p;
      ell->selection_note = note.str();
      return *ell;
    }
    note << "auto: line (" << how << ": p = " << p << " >= " << options.selection_alpha
         << ", the ellipse does not fit significantly better)";
    line.line_p_value = p;
    line.selection_note = note.str();
    return line;
  };

  if (options.use_theta && env.has_theta() && env.size() >= 6) {
    // F-test on the signed line residuals against (cos theta, sin theta). Robust losses
    // first drop points beyond 3 robust sigmas of the line (the outliers that the loss would
    // discount); an ellipse's own deviation from the line inflates that sigma, so it stays.
    std::vector<double> h;
    fit_detail::point_operations() += static_cast<std::int64_t>(env.size());
    for (const auto& p : env.response) h.push_back(nrm.dot(p - line.center) / L);
    const double cut = 3.0 * fit_detail::mad_scale(h);
    std::vector<std::size_t> keep;
    for (std::size_t i = 0; i < h.size(); ++i)
      if (options.loss == FitLoss::kNone || std::abs(h[i]) <= cut) keep.push_back(i);
    const auto m = static_cast<Eigen::Index>(keep.size());
    if (m >= 6) {
      Eigen::MatrixXd X(m, 3);
      Eigen::VectorXd y(m);
      for (Eigen::Index k = 0; k < m; ++k) {
        const std::size_t i = keep[static_cast<std::size_t>(k)];
        const double t = deg_to_rad(env.theta_deg[i]);
        X.row(k) << 1.0, std::cos(t), std::sin(t);
        y(k) = h[i];
      }
      Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(X);
      if (qr.rank() == 3) {
        const double ssr0 = (y.array() - y.mean()).square().sum();
        const double ssr1 = (X * qr.solve(y) - y).squaredNorm();
        const double dof = static_cast<double>(m) - 4.0;
        double p = 1.0;
        if (ssr1 <= tiny)
          p = ssr0 <= tiny ? 1.0 : 0.0;
        else  // survival function of F(2, dof) in closed form
          p = std::pow(1.0 + std::max(0.0, (ssr0 - ssr1) / ssr1), -dof / 2.0);
        return choose(p, "F-test on the directions, F(2, " + std::to_string(m - 4) + ")");
      }
    }
  }

  ell = fit_ellipse(env, options);
  if (sum_of_squares(ell->residuals, L) <= tiny) return choose(0.0, "exact fit to rounding");
  const double cost_l = cost_of(line, options.loss, ell->loss_scale, L);

  // Parametric bootstrap under the fitted line. Every fit of the statistic (the data's and
  // the draws') runs with the same iteration cap: on a noisy line the ellipse fit can wander
  // off to a -> infinity, and the test is only exact if data and draws see one procedure.
  constexpr int kBootstrapIterations = 50;
  FitOptions sim_opts = options;
  sim_opts.compute_covariance = false;
  sim_opts.max_iterations = std::min(options.max_iterations, kBootstrapIterations);
  sim_opts.use_theta = false;
  const EnvelopeFit ell_capped = ell->iterations > sim_opts.max_iterations || ell->used_theta
                                     ? fit_ellipse(env, sim_opts)
                                     : *ell;
  const double t_obs = cost_l / cost_of(ell_capped, options.loss, ell_capped.loss_scale, L);
  const double sigma = options.loss == FitLoss::kNone
                           ? L * std::sqrt(ssr_line / std::max(1.0, n - 2.0))
                           : fit_detail::mad_scale(line.residuals) * std::sqrt(n / (n - 2.0));
  std::vector<double> s;
  for (const auto& p : env.response) s.push_back(d.dot(p - line.center));
  std::mt19937_64 rng(options.seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  Envelope sim;
  sim.response.resize(env.size());
  const int B = options.bootstrap_samples;
  int exceed = 0, done = 0;
  for (; done < B; ++done) {
    for (std::size_t i = 0; i < env.size(); ++i)
      sim.response[i] = line.center + s[i] * d + sigma * (normal(rng) * d + normal(rng) * nrm);
    try {
      const EnvelopeFit sl = fit_line(sim, sim_opts);
      const EnvelopeFit se = fit_ellipse(sim, sim_opts);
      const double t =
          cost_of(sl, options.loss, se.loss_scale, L) / cost_of(se, options.loss, se.loss_scale, L);
      if (!(t < t_obs)) ++exceed;
    } catch (const InputError&) {
      ++exceed;  // a draw that cannot be fitted counts against the ellipse (conservative)
    }
    // Once p = (1 + exceed) / (B + 1) reaches alpha the line cannot be rejected any more.
    if ((1.0 + exceed) / (B + 1.0) >= options.selection_alpha) {
      ++done;
      break;
    }
  }
  const double p = (1.0 + exceed) / (B + 1.0);
  return choose(p, "parametric bootstrap, " + std::to_string(done) + " draws");
}

}  // namespace

std::string EnvelopeFit::BriefReport() const {
  std::ostringstream o;
  o.precision(6);
  o << "shape            " << to_string(shape) << "  (" << selection_note << ")\n";
  o << "points           " << n_points << (used_theta ? "  (directions used)" : "") << "\n";
  o << "center           " << center.x() << ", " << center.y();
  if (has_stderr) o << "   +- " << center_stderr.x() << ", " << center_stderr.y();
  o << "\nsemi_axes        " << a << ", " << b;
  if (has_stderr) o << "   +- " << a_stderr << ", " << b_stderr;
  o << "\ninclination_deg  ";
  if (inclination_deg) {
    o << *inclination_deg;
    if (inclination_stderr_deg) o << "   +- " << *inclination_stderr_deg;
  } else {
    o << "undefined (circle)";
  }
  o << "\nrms              " << rms << "\n";
  o << "loss             " << to_string(loss);
  if (loss != FitLoss::kNone) o << " (scale " << loss_scale << ")";
  o << "\nconverged        " << (converged ? "yes" : "no") << "\n";
  if (!has_stderr) o << "standard errors  not available\n";
  return o.str();
}

}  // namespace rendulic

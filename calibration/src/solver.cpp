// Ceres and NLopt back ends (solver.hpp; docs/calibration.md "Back ends").
#include "rendulic/calibration/solver.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <nlopt.hpp>
#include <random>
#include <sstream>

#include "rendulic/core/errors.hpp"

namespace rendulic::calibration {

std::string to_string(Backend b) {
  switch (b) {
    case Backend::kCeres:
      return "ceres";
    case Backend::kMultiStart:
      return "multistart";
    case Backend::kGlobal:
      return "global";
    case Backend::kLocalNlopt:
      return "bobyqa";
  }
  return "?";
}

Backend backend_from_string(const std::string& name) {
  for (Backend b : {Backend::kCeres, Backend::kMultiStart, Backend::kGlobal, Backend::kLocalNlopt})
    if (to_string(b) == name) return b;
  throw InputError("unknown back end '" + name + "' (known: ceres, multistart, global, bobyqa)");
}

bool SolverOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& m) {
    if (why) *why = m;
    return false;
  };
  if (global_algorithm != "GN_CRS2_LM" && global_algorithm != "GN_ISRES" &&
      global_algorithm != "GN_MLSL_LDS")
    return fail("global_algorithm must be GN_CRS2_LM, GN_ISRES or GN_MLSL_LDS");
  if (global_evaluations < 10 || local_evaluations < 10) return fail("evaluations must be >= 10");
  if (starts < 1) return fail("starts must be >= 1");
  if (max_iterations < 1) return fail("max_iterations must be >= 1");
  if (!(function_tolerance > 0 && gradient_tolerance > 0 && parameter_tolerance > 0))
    return fail("tolerances must be > 0");
  return identifiability.IsValid(why);
}

double objective_cost(const Objective& objective, const std::vector<double>& z) {
  std::vector<double> r(objective.num_residuals());
  if (!objective.residuals(z.data(), r.data())) return std::numeric_limits<double>::infinity();
  double s = 0.0;
  for (double x : r) s += x * x;
  return 0.5 * s;
}

namespace {

struct CeresRun {
  std::vector<double> z;
  double cost = std::numeric_limits<double>::infinity();
  bool converged = false;
  int iterations = 0;
  std::string message;
  std::string termination = "failure";
  std::vector<int> pinned;  // free parameters held on a bound (see run_ceres)
};

// Which criterion stopped Ceres, in the words of FitResult::termination.
std::string termination_of(const ceres::Solver::Summary& s) {
  if (s.termination_type == ceres::NO_CONVERGENCE) return "budget";
  if (s.termination_type != ceres::CONVERGENCE) return "failure";
  if (s.message.rfind("Gradient tolerance", 0) == 0) return "gradient";
  if (s.message.rfind("Function tolerance", 0) == 0) return "function";
  return "parameter";  // parameter tolerance, or the trust region shrank to nothing
}

// Stops Levenberg-Marquardt once the same free parameters have sat on a bound of the box for
// three accepted steps in a row: the fit is then crawling along the bound (see run_ceres).
class BoundWatch final : public ceres::IterationCallback {
 public:
  BoundWatch(const ParameterSpace& sp, const std::vector<double>* z, const std::vector<int>& skip)
      : sp_(sp), z_(z), skip_(skip) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& it) override {
    if (!it.step_is_successful) return ceres::SOLVER_CONTINUE;
    std::vector<int> on;
    for (int k = 0; k < sp_.size(); ++k) {
      if (std::find(skip_.begin(), skip_.end(), k) != skip_.end()) continue;
      const double lo = sp_.z_lower(k), hi = sp_.z_upper(k), tol = 1e-9 * (hi - lo);
      if ((*z_)[k] <= lo + tol || (*z_)[k] >= hi - tol) on.push_back(k);
    }
    count_ = !on.empty() && on == last_ ? count_ + 1 : (on.empty() ? 0 : 1);
    last_ = on;
    if (count_ >= 3) {
      stopped_ = true;
      return ceres::SOLVER_TERMINATE_SUCCESSFULLY;
    }
    return ceres::SOLVER_CONTINUE;
  }
  bool stopped() const { return stopped_; }

 private:
  const ParameterSpace& sp_;
  const std::vector<double>* z_;
  std::vector<int> skip_, last_;
  int count_ = 0;
  bool stopped_ = false;
};

CeresRun run_ceres_once(const Objective& obj, std::vector<double> z, const SolverOptions& o,
                        const std::vector<int>& pinned, const std::vector<int>& inward,
                        bool* stopped_on_bound) {
  const ParameterSpace& sp = obj.space();
  for (int k = 0; k < sp.size(); ++k) z[k] = std::clamp(z[k], sp.z_lower(k), sp.z_upper(k));
  ceres::Problem problem;
  problem.AddResidualBlock(obj.make_cost_function(), nullptr, z.data());
  for (int k = 0; k < sp.size(); ++k) {
    problem.SetParameterLowerBound(z.data(), k, sp.z_lower(k));
    problem.SetParameterUpperBound(z.data(), k, sp.z_upper(k));
  }
  if (static_cast<int>(pinned.size()) == sp.size()) {
    problem.SetParameterBlockConstant(z.data());
  } else if (!pinned.empty()) {
    problem.SetManifold(z.data(), new ceres::SubsetManifold(sp.size(), pinned));
  }
  ceres::Solver::Options so;
  so.linear_solver_type = ceres::DENSE_QR;
  so.max_num_iterations = o.max_iterations;
  so.function_tolerance = o.function_tolerance;
  // Relative to the cost at the start, so that the criterion does not depend on the units
  // and weights of the residuals (Ceres's own is absolute).
  so.gradient_tolerance = o.gradient_tolerance * std::max(objective_cost(obj, z), 1e-300);
  so.parameter_tolerance = o.parameter_tolerance;
  so.logging_type = o.progress ? ceres::PER_MINIMIZER_ITERATION : ceres::SILENT;
  so.minimizer_progress_to_stdout = o.progress;
  so.num_threads = 1;
  std::vector<int> skip = pinned;
  skip.insert(skip.end(), inward.begin(), inward.end());
  BoundWatch watch(sp, &z, skip);
  so.update_state_every_iteration = true;
  so.callbacks.push_back(&watch);
  ceres::Solver::Summary summary;
  ceres::Solve(so, &problem, &summary);
  *stopped_on_bound = watch.stopped();
  CeresRun run;
  run.z = z;
  run.pinned = pinned;
  run.iterations = static_cast<int>(summary.iterations.size());
  run.message = summary.message;
  run.termination = termination_of(summary);
  if (summary.termination_type == ceres::FAILURE || !std::isfinite(summary.final_cost)) {
    run.converged = false;
    run.termination = "failure";
    return run;
  }
  run.cost = summary.final_cost;
  run.converged = summary.termination_type == ceres::CONVERGENCE;
  return run;
}

// Levenberg-Marquardt inside the box, with an active set: Ceres projects a trust-region step
// onto the box but judges it by the unprojected model, so where the optimum lies on a bound
// (the data push a parameter out of its range) every step is judged too optimistic and the
// solver crawls. A free parameter left on a bound with the gradient pointing out of the box
// is therefore held there and the fit repeated, until no new parameter is held.
CeresRun run_ceres(const Objective& obj, std::vector<double> z, const SolverOptions& o) {
  const ParameterSpace& sp = obj.space();
  std::vector<int> pinned, inward;
  CeresRun run;
  int iterations = 0;
  for (int round = 0; round <= 2 * sp.size(); ++round) {
    bool on_bound = false;
    run = run_ceres_once(obj, z, o, pinned, inward, &on_bound);
    iterations += run.iterations;
    if (!std::isfinite(run.cost) || run.termination == "budget") break;
    z = run.z;
    Eigen::VectorXd r;
    Eigen::MatrixXd J;
    if (!obj.jacobian(z.data(), &r, &J)) break;
    const Eigen::VectorXd g = J.transpose() * r;
    bool more = false;
    for (int k = 0; k < sp.size(); ++k) {
      if (std::find(pinned.begin(), pinned.end(), k) != pinned.end()) continue;
      const double lo = sp.z_lower(k), hi = sp.z_upper(k), tol = 1e-9 * (hi - lo);
      const bool at_lo = z[k] <= lo + tol, at_hi = z[k] >= hi - tol;
      if ((at_lo && g(k) > 0.0) || (at_hi && g(k) < 0.0)) {
        pinned.push_back(k);
        more = true;
      } else if ((at_lo || at_hi) && std::find(inward.begin(), inward.end(), k) == inward.end()) {
        inward.push_back(k);  // on the bound but pulled inside: let it move, stop watching it
        more = more || on_bound;
      }
    }
    if (!more && !on_bound) break;
    std::sort(pinned.begin(), pinned.end());
  }
  run.iterations = iterations;
  run.pinned = pinned;
  return run;
}

// NLopt works on u in [0, 1]^p (the box in working coordinates) so that one step size and one
// tolerance fit every parameter.
struct NloptContext {
  const Objective* obj;
  std::vector<double> lo, hi;
  int evaluations = 0;
  double best = std::numeric_limits<double>::infinity();
  std::vector<double> best_u;
  std::vector<double> z_of(const std::vector<double>& u) const {
    std::vector<double> z(u.size());
    for (std::size_t k = 0; k < u.size(); ++k) z[k] = lo[k] + u[k] * (hi[k] - lo[k]);
    return z;
  }
};

double nlopt_function(const std::vector<double>& u, std::vector<double>&, void* data) {
  auto* c = static_cast<NloptContext*>(data);
  ++c->evaluations;
  const double f = objective_cost(*c->obj, c->z_of(u));
  if (f < c->best) {
    c->best = f;
    c->best_u = u;
  }
  // A failed model evaluation is a very bad point, but finite: BOBYQA's quadratic models
  // cannot take an infinity.
  return std::isfinite(f) ? f : 1e30;
}

nlopt::algorithm global_algorithm(const std::string& name) {
  if (name == "GN_ISRES") return nlopt::GN_ISRES;
  if (name == "GN_MLSL_LDS") return nlopt::GN_MLSL_LDS;
  return nlopt::GN_CRS2_LM;
}

// Runs one NLopt algorithm from u (in place); the context keeps the best point ever seen, which
// is what we continue from even when NLopt stops with an exception (round-off, forced stop).
std::string run_nlopt(nlopt::algorithm alg, NloptContext* c, std::vector<double>* u, int maxeval,
                      const SolverOptions& o) {
  const unsigned p = static_cast<unsigned>(u->size());
  nlopt::opt opt(alg, p);
  opt.set_lower_bounds(std::vector<double>(p, 0.0));
  opt.set_upper_bounds(std::vector<double>(p, 1.0));
  opt.set_min_objective(nlopt_function, c);
  opt.set_maxeval(maxeval);
  opt.set_xtol_rel(1e-10);
  opt.set_ftol_abs(1e-30);
  if (alg == nlopt::LN_BOBYQA) opt.set_initial_step(0.05);
  nlopt::opt local(nlopt::LN_BOBYQA, p);
  if (alg == nlopt::GN_MLSL_LDS) {
    local.set_xtol_rel(1e-8);
    local.set_maxeval(std::max(50, maxeval / 20));
    opt.set_local_optimizer(local);
  }
  std::string msg;
  double f = 0.0;
  try {
    const nlopt::result res = opt.optimize(*u, f);
    msg = std::string("nlopt ") + opt.get_algorithm_name() + " result " + std::to_string(res);
  } catch (const std::exception& e) {
    msg = std::string("nlopt ") + opt.get_algorithm_name() + " stopped: " + e.what();
  }
  if (!c->best_u.empty()) *u = c->best_u;
  (void)o;
  return msg;
}

}  // namespace

FitResult solve(const Objective& obj, const std::vector<double>& z0, const SolverOptions& o) {
  std::string why;
  if (!o.IsValid(&why)) throw InputError("calibration solver: " + why);
  const auto t0 = std::chrono::steady_clock::now();
  const ParameterSpace& sp = obj.space();
  const int p = sp.size();
  if (static_cast<int>(z0.size()) != p) throw InputError("calibration solver: start size mismatch");
  FitResult out;
  out.names = sp.names();
  out.backend = to_string(o.backend);
  out.jacobian = !obj.exact_derivatives() ? "numeric (central differences)"
                 : obj.integrated()       ? "autodiff (through the driver)"
                                          : "autodiff";
  std::ostringstream rep;
  std::vector<double> z = z0;
  bool converged = false;
  double cost = std::numeric_limits<double>::infinity();
  std::string termination = "failure";
  std::vector<int> pinned;

  if (o.backend == Backend::kCeres || o.backend == Backend::kMultiStart) {
    std::mt19937_64 rng(o.seed);
    std::uniform_real_distribution<double> unif(0.0, 1.0);
    const int starts = o.backend == Backend::kCeres ? 1 : o.starts;
    for (int s = 0; s < starts; ++s) {
      std::vector<double> zs = z0;
      if (s > 0)
        for (int k = 0; k < p; ++k)
          zs[k] = sp.z_lower(k) + unif(rng) * (sp.z_upper(k) - sp.z_lower(k));
      const CeresRun run = run_ceres(obj, zs, o);
      out.evaluations += run.iterations;
      rep << "ceres start " << s << ": cost " << run.cost << " after " << run.iterations
          << " iterations (" << run.message << "). ";
      if (run.cost < cost) {
        cost = run.cost;
        z = run.z;
        converged = run.converged;
        termination = run.termination;
        pinned = run.pinned;
      }
    }
  } else {
    NloptContext c{&obj, {}, {}, 0, std::numeric_limits<double>::infinity(), {}};
    for (int k = 0; k < p; ++k) {
      c.lo.push_back(sp.z_lower(k));
      c.hi.push_back(sp.z_upper(k));
    }
    std::vector<double> u(p);
    for (int k = 0; k < p; ++k)
      u[k] = std::clamp((z0[k] - c.lo[k]) / (c.hi[k] - c.lo[k]), 0.0, 1.0);
    if (o.backend == Backend::kGlobal) {
      nlopt::srand(o.seed);
      rep << run_nlopt(global_algorithm(o.global_algorithm), &c, &u, o.global_evaluations, o)
          << ", best cost " << c.best << " after " << c.evaluations << " evaluations. ";
    }
    const int before = c.evaluations;
    rep << run_nlopt(nlopt::LN_BOBYQA, &c, &u, o.local_evaluations, o) << ", best cost " << c.best
        << " after " << c.evaluations - before << " evaluations. ";
    out.evaluations += c.evaluations;
    z = c.z_of(u);
    cost = c.best;
    converged = std::isfinite(cost);
    termination = "budget";  // NLopt's own stopping rule; the polish says more
    if (o.polish && std::isfinite(cost)) {
      const CeresRun run = run_ceres(obj, z, o);
      out.evaluations += run.iterations;
      rep << "ceres polish: cost " << run.cost << " after " << run.iterations << " iterations ("
          << run.message << ").";
      if (run.cost <= cost) {
        z = run.z;
        cost = run.cost;
        converged = run.converged;
        termination = run.termination;
        pinned = run.pinned;
      }
    }
  }
  out.report = rep.str();
  out.z = z;
  out.params = sp.full(z);
  for (const auto& f : sp.free()) out.values.push_back(out.params[f.index]);
  out.cost = cost;
  out.converged = converged && std::isfinite(cost);
  out.termination = std::isfinite(cost) ? termination : "failure";
  for (int k : pinned) out.at_bound.push_back(out.names[k]);
  Eigen::VectorXd r;
  Eigen::MatrixXd J;
  if (std::isfinite(cost) && obj.jacobian(z.data(), &r, &J)) {
    out.rms = std::sqrt(r.squaredNorm() / r.size());
    // Parameters held on a bound are not estimated from the data: the uncertainty is that of
    // the others, and theirs is undetermined (+inf), with a warning that says why.
    std::vector<int> est;
    for (int k = 0; k < p; ++k)
      if (std::find(pinned.begin(), pinned.end(), k) == pinned.end()) est.push_back(k);
    const int q = static_cast<int>(est.size());
    Eigen::MatrixXd Jq(J.rows(), q);
    Eigen::VectorXd pv(q), d(q);
    std::vector<std::string> names;
    for (int j = 0; j < q; ++j) {
      const int k = est[j];
      Jq.col(j) = J.col(k);
      pv(j) = out.values[k];
      d(j) = sp.dp_dz(k, z[k]);
      names.push_back(out.names[k]);
    }
    const Uncertainty uq =
        q > 0 ? estimate_uncertainty(Jq, r, names, pv, d, o.identifiability) : Uncertainty{};
    out.uncertainty = uq;
    out.uncertainty.covariance = Eigen::MatrixXd::Zero(p, p);
    out.uncertainty.stderr_z =
        Eigen::VectorXd::Constant(p, std::numeric_limits<double>::infinity());
    out.uncertainty.correlation = Eigen::MatrixXd::Identity(p, p);
    out.uncertainty.determined.assign(p, false);
    for (int a = 0; a < q; ++a) {
      out.uncertainty.stderr_z(est[a]) = uq.stderr_z(a);
      out.uncertainty.determined[est[a]] = uq.determined[a];
      for (int b = 0; b < q; ++b) {
        out.uncertainty.covariance(est[a], est[b]) = uq.covariance(a, b);
        out.uncertainty.correlation(est[a], est[b]) = uq.correlation(a, b);
      }
    }
    for (int k : pinned) {
      const bool upper = z[k] >= sp.z_upper(k) - 1e-9 * (sp.z_upper(k) - sp.z_lower(k));
      std::ostringstream w;
      w << "parameter '" << out.names[k] << "' sits at its " << (upper ? "upper" : "lower")
        << " bound " << out.values[k]
        << ": the data push it beyond, so it is held there and not estimated";
      out.uncertainty.warnings.push_back(w.str());
    }
    for (int k = 0; k < p; ++k)
      out.stderr_.push_back(std::abs(sp.dp_dz(k, z[k])) * out.uncertainty.stderr_z(k));
    out.correlation = out.uncertainty.correlation;
  } else {
    out.converged = false;
    out.stderr_.assign(p, std::numeric_limits<double>::infinity());
    out.correlation = Eigen::MatrixXd::Identity(p, p);
    out.uncertainty.warnings.push_back("the model could not be evaluated at the final point");
    out.report += " Model evaluation failed at the final point.";
  }
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

}  // namespace rendulic::calibration

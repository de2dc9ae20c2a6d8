// Ceres and NLopt back ends (solver.hpp; docs/calibration.md "Back ends").
#include "rendulic/calibration/solver.hpp"

#include <glog/logging.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <limits>
#include <memory>
#include <nlopt.hpp>
#include <random>
#include <sstream>
#include <thread>

#include "cores.hpp"
#include "rendulic/core/decimal.hpp"
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
  if (threads < 0) return fail("threads must be >= 0");
  if (max_iterations < 1) return fail("max_iterations must be >= 1");
  if (!(function_tolerance > 0 && gradient_tolerance > 0 && parameter_tolerance > 0))
    return fail("tolerances must be > 0");
  return identifiability.IsValid(why);
}

double objective_cost(const Objective& objective, const std::vector<double>& z, FailureHint* hint) {
  std::vector<double> r(objective.num_residuals());
  if (!objective.residuals(z.data(), r.data(), hint))
    return std::numeric_limits<double>::infinity();
  double s = 0.0;
  for (double x : r) s += x * x;
  return 0.5 * s;
}

namespace {

// The likelihood of selection.hpp on one block: with s = |r_b|^2 = w m_b^2 (the block's weighted
// relative misfit) and x = s / (w nu_b^2),
//   rho(s) = N_b x             for x < 1   (the data's noise sets sigma_b),
//   rho(s) = N_b (ln x + 1)    for x >= 1  (sigma_b = m_b, profiled),
// i.e. -2 ln L_b up to a constant that depends on the data only; continuous with its first
// derivative at x = 1. Levenberg-Marquardt sees it through likelihood_block_model (solver.hpp).
class BlockLikelihood {
 public:
  BlockLikelihood(double components, double floor2) : n_(components), c_(floor2) {}
  void Evaluate(double s, double rho[3]) const {
    const double x = s / c_;
    if (x < 1.0) {
      rho[0] = n_ * x;
      rho[1] = n_ / c_;
      rho[2] = 0.0;
    } else {
      rho[0] = n_ * (std::log(x) + 1.0);
      rho[1] = n_ / s;
      rho[2] = -n_ / (s * s);
    }
  }

 private:
  double n_, c_;
};

}  // namespace

void likelihood_block_model(double n, double floor2, int m, int p, double* r, double* J) {
  double s = 0.0;
  for (int i = 0; i < m; ++i) s += r[i] * r[i];
  double rho[3];
  BlockLikelihood(n, floor2).Evaluate(s, rho);
  const double root1 = std::sqrt(rho[1]);
  if (s / floor2 < 1.0) {  // below the floor (BlockLikelihood's test): rho is linear in s
    for (int i = 0; i < m; ++i) r[i] *= root1;
    if (J)
      for (int k = 0; k < m * p; ++k) J[k] *= root1;
    return;
  }
  const double norm = std::sqrt(s);
  const double beta = std::sqrt(rho[1] * s / rho[0]);  // 1 / sqrt(ln x + 1)
  if (J) {
    std::vector<double> rt_j(static_cast<std::size_t>(p), 0.0);  // rhat^T J
    for (int i = 0; i < m; ++i)
      for (int k = 0; k < p; ++k) rt_j[k] += r[i] / norm * J[i * p + k];
    for (int i = 0; i < m; ++i)
      for (int k = 0; k < p; ++k)
        J[i * p + k] = root1 * (J[i * p + k] - (1.0 - beta) * r[i] / norm * rt_j[k]);
  }
  const double stretch = std::sqrt(rho[0]) / norm;
  for (int i = 0; i < m; ++i) r[i] *= stretch;
}

namespace {

double block_floor2(const ResidualBlock& b) {
  return b.weight * std::max(b.noise * b.noise, 1e-24);
}

// sum_b rho_b at residuals r (the likelihood cost is half of it).
double likelihood_sum(const Objective& obj, const double* r, std::vector<double>* rho1 = nullptr) {
  double sum = 0.0;
  if (rho1) rho1->clear();
  for (const auto& b : obj.blocks()) {
    double s = 0.0;
    for (int i = 0; i < b.size; ++i) s += r[b.offset + i] * r[b.offset + i];
    double rho[3];
    BlockLikelihood(b.size, block_floor2(b)).Evaluate(s, rho);
    sum += rho[0];
    if (rho1) rho1->push_back(rho[1]);
  }
  return sum;
}

// The cost the back ends minimise: 0.5 |r|^2, or 0.5 sum_b rho_b with the likelihood.
double cost_of(const Objective& obj, const std::vector<double>& z, bool likelihood,
               FailureHint* hint = nullptr) {
  if (!likelihood) return objective_cost(obj, z, hint);
  std::vector<double> r(obj.num_residuals());
  if (!obj.residuals(z.data(), r.data(), hint)) return std::numeric_limits<double>::infinity();
  return 0.5 * likelihood_sum(obj, r.data());
}

// One evaluation of the whole objective (all blocks at once: the predictions of a state are
// shared by its blocks, and the probes run in parallel), cached for the per-block cost
// functions of the likelihood, which Ceres calls one after the other at the same point.
class SharedEvaluation {
 public:
  explicit SharedEvaluation(const Objective& obj) : obj_(obj), f_(obj.make_cost_function()) {}
  bool get(const double* z, bool jacobian, const double** r, const double** j) {
    const int p = obj_.num_parameters(), n = obj_.num_residuals();
    const bool same = !key_.empty() && std::equal(key_.begin(), key_.end(), z);
    if (!same || (jacobian && !has_j_)) {
      key_.assign(z, z + p);
      r_.resize(n);
      has_j_ = jacobian;
      if (jacobian) j_.resize(static_cast<std::size_t>(n) * p);
      double* jac[1] = {j_.data()};
      const double* params[1] = {z};
      ok_ = f_->Evaluate(params, r_.data(), jacobian ? jac : nullptr);
    }
    *r = r_.data();
    *j = j_.data();
    return ok_;
  }

 private:
  const Objective& obj_;
  std::unique_ptr<ceres::CostFunction> f_;
  std::vector<double> key_, r_, j_;  // j_ row-major n x p
  bool has_j_ = false, ok_ = false;
};

// Block b of the shared evaluation; with `likelihood`, as likelihood_block_model presents it.
class BlockSlice final : public ceres::CostFunction {
 public:
  BlockSlice(SharedEvaluation* shared, const ResidualBlock& b, int p, bool likelihood)
      : shared_(shared),
        offset_(b.offset),
        size_(b.size),
        p_(p),
        likelihood_(likelihood),
        floor2_(block_floor2(b)) {
    set_num_residuals(b.size);
    mutable_parameter_block_sizes()->push_back(p);
  }
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    const double *r = nullptr, *j = nullptr;
    const bool jac = jacobians != nullptr && jacobians[0] != nullptr;
    if (!shared_->get(parameters[0], jac, &r, &j)) return false;
    std::copy(r + offset_, r + offset_ + size_, residuals);
    if (jac)
      std::copy(j + static_cast<std::size_t>(offset_) * p_,
                j + static_cast<std::size_t>(offset_ + size_) * p_, jacobians[0]);
    if (likelihood_)
      likelihood_block_model(size_, floor2_, size_, p_, residuals, jac ? jacobians[0] : nullptr);
    return true;
  }

 private:
  SharedEvaluation* shared_;
  int offset_, size_, p_;
  bool likelihood_;
  double floor2_;
};

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

// The cost of a run: plain least squares, least squares with fixed block weights (`frozen`),
// or the likelihood.
struct CostModel {
  bool likelihood = false;
  const std::vector<double>* frozen = nullptr;
};

// Per-block factors of the gradient J^T r of the cost model at residuals r.
std::vector<double> block_factors(const Objective& obj, const double* r, const CostModel& cm) {
  if (cm.frozen) return *cm.frozen;
  if (cm.likelihood) {
    std::vector<double> rho1;
    likelihood_sum(obj, r, &rho1);
    return rho1;
  }
  return std::vector<double>(obj.blocks().size(), 1.0);
}

// Trials of Ceres's line search along a projected step (run_ceres_once says why so few).
constexpr int kLineSearchTrials = 3;

CeresRun run_ceres_once(const Objective& obj, std::vector<double> z, const SolverOptions& o,
                        const CostModel& cm, const std::vector<int>& pinned,
                        const std::vector<int>& inward, bool* stopped_on_bound) {
  const ParameterSpace& sp = obj.space();
  for (int k = 0; k < sp.size(); ++k) z[k] = std::clamp(z[k], sp.z_lower(k), sp.z_upper(k));
  ceres::Problem problem;
  SharedEvaluation shared(obj);
  if (cm.likelihood || cm.frozen) {
    for (std::size_t i = 0; i < obj.blocks().size(); ++i) {
      const ResidualBlock& b = obj.blocks()[i];
      // Fixed weights are a plain scaled least-squares block; the likelihood is presented by
      // the block itself (likelihood_block_model), not as a Ceres loss, whose corrector leaves
      // out a concave loss's curvature entirely.
      ceres::LossFunction* loss =
          cm.frozen ? new ceres::ScaledLoss(nullptr, (*cm.frozen)[i], ceres::TAKE_OWNERSHIP)
                    : nullptr;
      problem.AddResidualBlock(new BlockSlice(&shared, b, sp.size(), !cm.frozen), loss, z.data());
    }
  } else {
    problem.AddResidualBlock(obj.make_cost_function(), nullptr, z.data());
  }
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
  // A parameter the data barely see (a column of J near zero) would otherwise get Ceres's
  // minimal damping (1e-6) and take steps of order one whatever the trust region, straight
  // into regions where the law cannot be evaluated; this damps it like a column of norm 0.03.
  so.min_lm_diagonal = 1e-3;
  so.max_num_iterations = o.max_iterations;
  // On a bounded problem Ceres judges every projected step by an Armijo search along it, from
  // the full step down. For the integrated laws a step that fails lands where the law is stiff
  // (hundreds of substeps a probe), and the default 20 trials were half of
  // elastoplastic_fabric's fit; after 3 the step is given up and the trust region shrinks
  // instead (docs/calibration.md "When to stop": 7.0 -> 4.7 s idle wall on quick, the same fit
  // within 0.3 standard errors; 2 trials lose the basin).
  so.max_num_line_search_step_size_iterations = kLineSearchTrials;
  // Ceres's default cubic interpolation asks for the slope at each trial point, i.e. a whole
  // Jacobian (passes of Jets through the driver) at points that then fail or are rejected; the
  // quadratic one needs only their cost (the slope at the start is known). Half the Jacobians
  // of elastoplastic_fabric's fit on quick.toml, the fit within 0.15 standard errors
  // (docs/calibration.md "When to stop").
  so.line_search_interpolation_type = ceres::QUADRATIC;
  so.function_tolerance = o.function_tolerance;
  // Relative to the cost at the start, so that the criterion does not depend on the units
  // and weights of the residuals (Ceres's own is absolute).
  const double start_cost = cost_of(obj, z, o.likelihood);
  // A cost that is not finite there (a datum or prediction beyond the doubles) made the
  // tolerance nan, and Ceres blamed its own configuration ("Solver::Options::gradient_tolerance
  // = nan"); an infinite one made any gradient small enough to stop at once.
  if (!std::isfinite(start_cost)) {
    CeresRun run;
    run.z = z;
    run.pinned = pinned;
    run.message = "the objective at the start point is " + decimal_g(start_cost) +
                  " (a datum or a prediction is not finite there)";
    return run;
  }
  so.gradient_tolerance = o.gradient_tolerance * std::max(start_cost, 1e-300);
  if (cm.frozen) {
    std::vector<double> r(obj.num_residuals());
    double c = 0.0;
    if (obj.residuals(z.data(), r.data()))
      for (std::size_t i = 0; i < obj.blocks().size(); ++i)
        for (int k = 0; k < obj.blocks()[i].size; ++k)
          c +=
              0.5 * (*cm.frozen)[i] * r[obj.blocks()[i].offset + k] * r[obj.blocks()[i].offset + k];
    so.gradient_tolerance = o.gradient_tolerance * std::max(c, 1e-300);
  }
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
  {
    const cores::FitSlot slot(o.threads);
    ceres::Solve(so, &problem, &summary);
  }
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
CeresRun run_ceres_model(const Objective& obj, std::vector<double> z, const SolverOptions& o,
                         const CostModel& cm) {
  const ParameterSpace& sp = obj.space();
  std::vector<int> pinned, inward;
  CeresRun run;
  int iterations = 0;
  for (int round = 0; round <= 2 * sp.size(); ++round) {
    bool on_bound = false;
    run = run_ceres_once(obj, z, o, cm, pinned, inward, &on_bound);
    iterations += run.iterations;
    if (!std::isfinite(run.cost) || run.termination == "budget") break;
    z = run.z;
    Eigen::VectorXd r;
    Eigen::MatrixXd J;
    if (!obj.jacobian(z.data(), &r, &J)) break;
    // The gradient of the run's cost: each block's J^T r scaled by its factor.
    const std::vector<double> f = block_factors(obj, r.data(), cm);
    Eigen::VectorXd g = Eigen::VectorXd::Zero(sp.size());
    for (std::size_t b = 0; b < obj.blocks().size(); ++b) {
      const ResidualBlock& blk = obj.blocks()[b];
      g += f[b] * J.middleRows(blk.offset, blk.size).transpose() * r.segment(blk.offset, blk.size);
    }
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

// Levenberg-Marquardt for the solver's cost. The likelihood can have several maxima: its
// profiled block variances let a law give up a block it cannot fit (an elastic law the path,
// say) for closer fits of the others, or not. Two starts, the better kept: the weights
// following the fit from the first step, and first a fit with the block weights held at their
// values at the start point (which finds the maxima the first would leave for a compromise).
// The held-weights fit only finds a start for the second following fit, which converges with
// the full tolerances; it stops once an iteration lowers its cost by less than
// kStartFunctionTolerance, far below the statistical resolution of the cost (a change of 0.5
// in a cost of thousands). The two starts are independent and run on two threads for the
// built-in laws (their evaluation is reentrant; a UMAT may keep state of its own, so its
// starts run one after the other; so do all with SolverOptions::threads = 1): the same results
// as in sequence; once one start is done, the other's Jacobians take the free core
// (docs/calibration.md "Threads").
constexpr double kStartFunctionTolerance = 1e-6;

CeresRun run_ceres(const Objective& obj, std::vector<double> z, const SolverOptions& o) {
  if (!o.likelihood) return run_ceres_model(obj, z, o, {});
  const auto second_start = [&obj, &z, &o]() {
    CeresRun out;  // cost +inf: no second start
    std::vector<double> r(obj.num_residuals());
    if (!obj.residuals(z.data(), r.data())) return out;
    const std::vector<double> frozen = block_factors(obj, r.data(), {true, nullptr});
    SolverOptions start_options = o;
    start_options.function_tolerance = std::max(o.function_tolerance, kStartFunctionTolerance);
    const CeresRun first = run_ceres_model(obj, z, start_options, {false, &frozen});
    if (!std::isfinite(first.cost)) {
      out.iterations = first.iterations;
      return out;
    }
    out = run_ceres_model(obj, first.z, o, {true, nullptr});
    out.iterations += first.iterations;
    return out;
  };
  CeresRun best, second;
  // With `progress` each Ceres run prints its iterations: one after the other, to be read.
  if (obj.exact_derivatives() && !o.progress && cores::limit(o.threads) > 1) {
    std::exception_ptr failure;
    std::thread other([&] {
      try {
        second = second_start();
      } catch (...) {
        failure = std::current_exception();
      }
    });
    try {
      best = run_ceres_model(obj, z, o, {true, nullptr});
    } catch (...) {
      other.join();
      throw;
    }
    other.join();
    if (failure) std::rethrow_exception(failure);
  } else {
    best = run_ceres_model(obj, z, o, {true, nullptr});
    second = second_start();
  }
  const int iterations = best.iterations + second.iterations;
  if (second.cost < best.cost) best = second;
  best.iterations = iterations;
  return best;
}

// NLopt works on u in [0, 1]^p (the box in working coordinates) so that one step size and one
// tolerance fit every parameter.
struct NloptContext {
  const Objective* obj;
  bool likelihood = false;
  std::vector<double> lo, hi;
  int evaluations = 0;
  double best = std::numeric_limits<double>::infinity();
  std::vector<double> best_u;
  FailureHint hint;  // NLopt's points are one stream
  std::vector<double> z_of(const std::vector<double>& u) const {
    std::vector<double> z(u.size());
    for (std::size_t k = 0; k < u.size(); ++k) z[k] = lo[k] + u[k] * (hi[k] - lo[k]);
    return z;
  }
};

double nlopt_function(const std::vector<double>& u, std::vector<double>&, void* data) {
  auto* c = static_cast<NloptContext*>(data);
  ++c->evaluations;
  const double f = cost_of(*c->obj, c->z_of(u), c->likelihood, &c->hint);
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
    NloptContext c{&obj, o.likelihood, {}, {}, 0, std::numeric_limits<double>::infinity(), {}, {}};
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
      // The polish judges convergence whichever point is kept: NLopt stops by its evaluation
      // budget, and its best point, if the polish cannot confirm it as an optimum (it ran out
      // of iterations), is not a converged fit, however close the polish's own cost.
      converged = run.converged;
      if (run.converged) termination = run.termination;
      if (run.cost <= cost) {
        z = run.z;
        cost = run.cost;
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
    if (o.likelihood) {
      // The weighted least-squares problem the likelihood is at its optimum: each block scaled
      // by sqrt(rho_b'), i.e. by sqrt(N_b) / sigma_b.
      std::vector<double> rho1;
      likelihood_sum(obj, r.data(), &rho1);
      for (std::size_t b = 0; b < obj.blocks().size(); ++b) {
        const ResidualBlock& blk = obj.blocks()[b];
        const double f = std::sqrt(rho1[b]);
        r.segment(blk.offset, blk.size) *= f;
        J.middleRows(blk.offset, blk.size) *= f;
      }
    }
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
    out.uncertainty.no_effect.assign(p, false);
    for (int a = 0; a < q; ++a) {
      out.uncertainty.stderr_z(est[a]) = uq.stderr_z(a);
      out.uncertainty.determined[est[a]] = uq.determined[a];
      out.uncertainty.no_effect[est[a]] = uq.no_effect[a];
      for (int b = 0; b < q; ++b) {
        out.uncertainty.covariance(est[a], est[b]) = uq.covariance(a, b);
        out.uncertainty.correlation(est[a], est[b]) = uq.correlation(a, b);
      }
    }
    for (int k : pinned) {
      const bool upper = z[k] >= sp.z_upper(k) - 1e-9 * (sp.z_upper(k) - sp.z_lower(k));
      std::ostringstream w;
      w << "parameter '" << out.names[k] << "' ended on its " << (upper ? "upper" : "lower")
        << " bound " << out.values[k]
        << " with the data pulling it beyond: it is held there and not estimated";
      out.uncertainty.warnings.push_back(w.str());
    }
    if (!pinned.empty()) {
      // A parameter may reach its bound because the data cannot tell it from others (a flat
      // valley ends on the bound): the rank test on every free parameter says so.
      Eigen::VectorXd pv(p), d(p);
      for (int k = 0; k < p; ++k) {
        pv(k) = out.values[k];
        d(k) = sp.dp_dz(k, z[k]);
      }
      const Uncertainty all = estimate_uncertainty(J, r, out.names, pv, d, o.identifiability);
      for (const auto& w : all.warnings)
        if (w.rfind("rank-deficient", 0) == 0) out.uncertainty.warnings.push_back(w);
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

void quiet_solver_logging() {
  if (FLAGS_minloglevel < google::GLOG_FATAL) FLAGS_minloglevel = google::GLOG_FATAL;
}

}  // namespace rendulic::calibration

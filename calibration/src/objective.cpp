// The calibration objective and its parameter space (objective.hpp): the
// weighting and normalisation are documented in docs/calibration.md "Objectives, weights and
// normalisation".
#include "rendulic/calibration/objective.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <exception>
#include <mutex>
#include <thread>

#include "cores.hpp"
#include "law_dispatch.hpp"
#include "rendulic/core/affine_map.hpp"
#include "rendulic/core/conventions.hpp"
#include "rendulic/core/decimal.hpp"
#include "rendulic/core/errors.hpp"
#include "rendulic/core/option_table.hpp"
#include "rendulic/models/driver_core.hpp"
#include "rendulic/models/law_model.hpp"
#include "rendulic/models/paths.hpp"
#include "rendulic/models/umat.hpp"

namespace rendulic::calibration {

using models::value_of;

// ---------------------------------------------------------------- parameter space

ParameterSpace::ParameterSpace(const models::Law& law, const std::vector<double>& values,
                               const std::vector<std::string>& free,
                               const std::map<std::string, std::pair<double, double>>& bounds)
    : base_(values) {
  const auto& info = law.parameter_info();
  if (values.size() != info.size())
    throw InputError(std::string(law.name()) + " takes " + std::to_string(info.size()) +
                     " parameters, got " + std::to_string(values.size()));
  // An unknown name first: `--free B,B` for a law without B is wrong for that reason, and
  // "listed twice" would send the user to fix the wrong thing.
  for (const auto& name : free)
    if (law.parameter_index(name) < 0) throw InputError(law.unknown_parameter(name));
  if (const std::string* again = first_repeat(free))
    throw InputError("parameter '" + *again + "' listed twice");
  for (const auto& name : free) {
    const int i = law.parameter_index(name);
    FreeParameter f;
    f.name = name;
    f.index = i;
    f.lower = info[i].lower;
    f.upper = info[i].upper;
    if (auto it = bounds.find(name); it != bounds.end()) {
      if (!(it->second.first < it->second.second) || it->second.first < info[i].lower ||
          it->second.second > info[i].upper)
        throw InputError("search bounds of '" + name + "' must lie within [" +
                         decimal_g(info[i].lower) + ", " + decimal_g(info[i].upper) +
                         "] with lower < upper");
      f.lower = it->second.first;
      f.upper = it->second.second;
    }
    // Two decades or more of a positive parameter: search in log space, where relative changes
    // are what matters and the parameter stays positive by construction.
    f.log = f.lower > 0.0 && f.upper / f.lower >= 100.0;
    base_[i] = std::clamp(base_[i], f.lower, f.upper);
    free_.push_back(f);
  }
  for (const auto& [name, box] : bounds)
    if (std::find(free.begin(), free.end(), name) == free.end())
      throw InputError("search bounds given for '" + name + "', not free");
}

std::vector<std::string> ParameterSpace::names() const {
  std::vector<std::string> n;
  for (const auto& f : free_) n.push_back(f.name);
  return n;
}

std::vector<double> ParameterSpace::full(const std::vector<double>& z) const {
  std::vector<double> p(base_.size());
  full(z.data(), p.data());
  return p;
}

std::vector<double> ParameterSpace::to_z(const std::vector<double>& v) const {
  std::vector<double> z;
  for (const auto& f : free_) z.push_back(f.log ? std::log(v[f.index]) : v[f.index]);
  return z;
}

double ParameterSpace::z_lower(int k) const {
  return free_[k].log ? std::log(free_[k].lower) : free_[k].lower;
}
double ParameterSpace::z_upper(int k) const {
  return free_[k].log ? std::log(free_[k].upper) : free_[k].upper;
}
double ParameterSpace::dp_dz(int k, double z) const { return free_[k].log ? std::exp(z) : 1.0; }

bool ObjectiveOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& m) {
    if (why) *why = m;
    return false;
  };
  for (double w :
       {weight_stress, weight_fabric, weight_features, weight_path_stress, weight_path_fabric})
    if (!(w >= 0.0) || !std::isfinite(w)) return fail("block weights must be finite and >= 0");
  if (!envelope_points && !envelope_features && !path)
    return fail("at least one of envelope_points, envelope_features, path must be on");
  if (!(fabric_scale_min >= 0.0)) return fail("fabric_scale_min must be >= 0");
  return step.IsValid(why);
}

// ---------------------------------------------------------------- the kernel

namespace {

template <typename T>
Eigen::Matrix<T, 2, 1> pair_of(const models::Mat3<T>& q) {
  return {T(kSqrt2) * T(0.5) * (q(1, 1) + q(2, 2)), q(0, 0)};
}

}  // namespace

struct EnvTask {
  int state = 0;  // index into Impl::states
  EnvelopeRecord env;
  bool integrated = false;
  int stress_offset = -1, fabric_offset = -1, features_offset = -1, fabric_features_offset = -1;
  double stress_scale = 1.0, fabric_scale = 1.0;
  double stress_w = 0.0, fabric_w = 0.0, features_w = 0.0;  // sqrt(weight / n) / scale
  double fabric_features_w = 0.0;
  Eigen::Matrix<double, 3, Eigen::Dynamic> projection;
  Eigen::Matrix<double, 3, 2> data_features, data_fabric_features;
};

struct PathTask {
  bool active = false;
  int stress_offset = -1, fabric_offset = -1;
  double stress_w = 0.0, fabric_w = 0.0;
};

struct KernelBase {
  virtual ~KernelBase() = default;
  virtual bool residuals(const double* z, double* r, FailureHint* hint) const = 0;
  virtual ceres::CostFunction* cost_function() const = 0;
  virtual bool envelope(const double* p, const StateData& s, const EnvelopeRecord& probes,
                        bool integrated, EnvelopeRecord* out) const = 0;
  virtual bool path(const double* p, PathData* out) const = 0;
  virtual DriverLoad driver_load(const double*) const { return {}; }

 protected:
  // A law's envelope over the data's probe set: the probes' name, amplitude, directions and
  // strain with the law's pairs (stored as "model", docs/results.md "/calibration").
  static EnvelopeRecord model_record(const EnvelopeRecord& probes,
                                     std::vector<Eigen::Vector2d> stress,
                                     std::vector<Eigen::Vector2d> fabric) {
    EnvelopeRecord out;
    out.name = probes.name;
    out.method = "model";
    out.amplitude = probes.amplitude;
    out.theta_deg = probes.theta_deg;
    out.strain = probes.strain;
    out.stress = std::move(stress);
    out.fabric = std::move(fabric);
    return out;
  }

  // The law's path states as PathData at the calibration's path samples.
  static void fill_path(const std::vector<models::MaterialState>& states, const PathData& data,
                        PathData* out) {
    out->eps_dev = data.eps_dev;
    out->stress.clear();
    out->fabric.clear();
    for (const auto& y : states) {
      out->stress.push_back(y.stress);
      out->fabric.push_back(y.fabric);
    }
    out->volume_fraction = data.volume_fraction;
  }
};

struct Objective::Impl {
  Impl(std::string law, ParameterSpace sp, const ObjectiveOptions& o)
      : law_name(std::move(law)), space(std::move(sp)), options(o) {}
  std::string law_name;
  ParameterSpace space;
  ObjectiveOptions options;
  std::vector<StateData> states;
  PathData path;
  std::vector<EnvTask> tasks;
  PathTask path_task;
  std::vector<ResidualBlock> blocks;
  int n_residuals = 0;
  bool any_integrated = false;
  // The law has a yield surface (models::kHasYieldSurface), so an elastic amplitude is no
  // promise of an elastic response: its small probes are integrated as well. A UMAT's are not:
  // the adapter cannot tell whether it has one (docs/umat.md "Calibration").
  bool yield_surface = false;
  // Whether the prediction of `env` is integrated by the driver or one evaluation of the rate
  // law: kAuto integrates every envelope of a law with a yield surface, and the others' above
  // the elastic amplitude (docs/calibration.md "Predictions and derivatives").
  bool integrated(const EnvelopeRecord& env) const {
    return options.prediction == Prediction::kIntegrated ||
           (options.prediction == Prediction::kAuto && (yield_surface || !env.elastic()));
  }
  std::unique_ptr<KernelBase> kernel;
  // Every evaluation (values, or values and Jacobian) since construction, the failed ones, and
  // those failed because a prediction needed more driver substeps than options.step allows
  // (Objective::tally).
  mutable std::atomic<long> evaluations{0}, failed{0}, failed_on_limit{0};
  // The parts of the residuals: kPath, or an envelope task's index; kNoPart in a FailureHint
  // that holds none. An evaluation starts where its stream's last one failed (FailureHint),
  // so that a trial point that fails where the last one did (the stiff probe of a fit near
  // the substep cap) fails before the other predictions are integrated. The order changes no
  // value: every probe starts from its state, every part writes its own residuals
  // (docs/calibration.md "When to stop").
  static constexpr int kPath = -1, kNoPart = -2;
  static_assert(FailureHint{}.part == kNoPart);
  // Why the last failed evaluation failed, where the law says (a UMAT's driver: its NaN, its
  // PNEWDT cuts); evaluations run side by side, hence the lock.
  mutable std::mutex failure_mutex;
  mutable std::string failure;
  void note_failure(const std::string& why) const {
    std::lock_guard<std::mutex> lock(failure_mutex);
    failure = why;
  }
  bool count(bool ok, bool on_limit) const {
    ++evaluations;
    if (!ok) ++failed;
    if (!ok && on_limit) ++failed_on_limit;
    return ok;
  }
};

namespace {

// Whether every residual is finite: an evaluation with a NaN or an infinity fails (Ceres then
// tries a shorter step) instead of handing it on.
template <typename T>
bool all_finite(const T* r, int n) {
  for (int i = 0; i < n; ++i)
    if (!std::isfinite(value_of(r[i]))) return false;
  return true;
}

template <class M>
class Kernel final : public KernelBase {
 public:
  explicit Kernel(const Objective::Impl* o) : o_(o) {}

  // How one part of an evaluation ended: completed by some unit, or failed in an integration
  // (at which probe, whether on the substep limit). Neither: stopped by another unit's
  // failure, or its start state inadmissible.
  struct PartEnd {
    std::atomic<bool> done{false}, failed{false}, on_limit{false};
    std::atomic<int> probe{0};
  };

  // What the units of one evaluation share: how each part ended, and where the stream's last
  // failure was (its hint, copied so that every unit sees one order).
  struct EvalContext {
    // A prediction failed: the evaluation fails whatever the others give, so the units still
    // running stop at their next probe or path increment.
    std::atomic<bool> stop{false};
    int fail_part = Objective::Impl::kNoPart, fail_probe = 0;
    int path = 0;               // 1 with a path part (kPath), which comes first in ends
    std::vector<PartEnd> ends;  // by part + path
    EvalContext(const FailureHint& hint, int parts, int path_)
        : fail_part(hint.part), fail_probe(hint.probe), path(path_), ends(parts) {}
    PartEnd& end(int part) { return ends[static_cast<std::size_t>(part + path)]; }
    // The part of the k-th unit in evaluation order (kPath, or a task index): the last
    // failure's part first, then the others in their order.
    int part(int k) const {
      const int parts = static_cast<int>(ends.size());
      const int hint = fail_part + path;  // the failed part's place in the natural order
      if (fail_part == Objective::Impl::kNoPart || hint < 0 || hint >= parts) return k - path;
      if (k == 0) return fail_part;
      return (k <= hint ? k - 1 : k) - path;
    }
  };

  int path_parts() const { return o_->path_task.active ? 1 : 0; }
  int parts() const { return path_parts() + static_cast<int>(o_->tasks.size()); }
  EvalContext context(const FailureHint* hint) const {
    return EvalContext(hint ? *hint : FailureHint{}, parts(), path_parts());
  }

  // The residuals' values, part by part in the evaluation's order on the caller's thread,
  // until one fails. Ceres's evaluations cut these into parts that may take a second thread
  // (JetCost below).
  bool eval(const double* z, double* r, EvalContext* ctx) const {
    for (int k = 0; k < parts(); ++k)
      if (!run_part<double>(z, r, ctx->part(k), ctx)) return false;
    return true;
  }

  // One part, marked done in ctx if it completes.
  template <typename T>
  bool run_part(const T* z, T* r, int part, EvalContext* ctx) const {
    if (!eval_part<T>(z, r, part, ctx)) return false;
    ctx->end(part).done = true;
    return true;
  }

  // Counts an evaluation whose units all completed (`units_ok`) or not. A failed one failed
  // "on the substep limit" if the first part in the evaluation's order that fails failed
  // there, and the stream's hint moves to that part. With a helper thread, a later part may
  // fail first and stop an earlier one before its own end: `again(part, ctx)` runs that part
  // alone (in the evaluation's own scalar) to its end, so that the verdict is the one of a
  // single thread, not of which part failed first in time (docs/calibration.md "When to
  // stop").
  template <class Again>
  bool finish(bool units_ok, const double* r, EvalContext* ctx, FailureHint* hint,
              const Again& again) const {
    if (units_ok) return o_->count(all_finite(r, o_->n_residuals), false);
    for (int k = 0; k < parts(); ++k) {
      const int part = ctx->part(k);
      const PartEnd& e = ctx->end(part);
      if (e.done) continue;
      if (e.failed) return o_->count(false, verdict(e, part, hint));
      EvalContext alone(FailureHint{ctx->fail_part, ctx->fail_probe}, parts(), path_parts());
      if (!again(part, &alone)) return o_->count(false, verdict(alone.end(part), part, hint));
    }
    return o_->count(false, false);  // not reached: a failed unit leaves its part not done
  }
  // finish() for the residuals' values at z.
  bool finish_values(bool units_ok, const double* z, const double* r, EvalContext* ctx,
                     FailureHint* hint) const {
    return finish(units_ok, r, ctx, hint, [&](int part, EvalContext* alone) {
      std::vector<double> scratch(static_cast<std::size_t>(o_->n_residuals));
      return run_part<double>(z, scratch.data(), part, alone);
    });
  }
  // A failed part's verdict: whether on the substep limit; the hint moves there.
  static bool verdict(const PartEnd& e, int part, FailureHint* hint) {
    if (hint) *hint = {part, e.failed ? e.probe.load() : 0};
    return e.failed && e.on_limit;
  }

  // One part of the residuals: the path's (part -1) or envelope task `part`'s. The parts are
  // independent, and each computes as it does inside eval(): the same bits.
  template <typename T>
  bool eval_part(const T* z, T* r, int part, EvalContext* ctx) const {
    T p[M::kCount];
    o_->space.full(z, p);
    double pd[M::kCount];
    for (int i = 0; i < M::kCount; ++i) pd[i] = value_of(p[i]);
    return part < 0 ? path_residuals<T>(p, pd, r, ctx) : task_residuals<T>(part, p, pd, r, ctx);
  }

  // Residuals of one envelope task.
  template <typename T>
  bool task_residuals(int index, const T* p, const double* pd, T* r, EvalContext* ctx) const {
    const EnvTask& t = o_->tasks[static_cast<std::size_t>(index)];
    std::vector<Eigen::Matrix<T, 2, 1>> ps, pf;
    const StateData& s = o_->states[t.state];
    if (!predict<T>(p, pd, s, t.env, t.integrated, &ps, &pf, nullptr, ctx, index)) return false;
    const int m = t.env.size();
    if (t.stress_offset >= 0)
      for (int i = 0; i < m; ++i)
        for (int c = 0; c < 2; ++c)
          r[t.stress_offset + 2 * i + c] = t.stress_w * (ps[i](c) - T(t.env.stress[i](c)));
    if (t.fabric_offset >= 0)
      for (int i = 0; i < m; ++i)
        for (int c = 0; c < 2; ++c)
          r[t.fabric_offset + 2 * i + c] = t.fabric_w * (pf[i](c) - T(t.env.fabric[i](c)));
    if (t.features_offset >= 0)
      for (int c = 0; c < 2; ++c)
        for (int k = 0; k < 3; ++k) {
          T f = T(0);
          for (int i = 0; i < m; ++i) f += T(t.projection(k, i)) * ps[i](c);
          r[t.features_offset + 3 * c + k] = t.features_w * (f - T(t.data_features(k, c)));
        }
    if (t.fabric_features_offset >= 0)
      for (int c = 0; c < 2; ++c)
        for (int k = 0; k < 3; ++k) {
          T f = T(0);
          for (int i = 0; i < m; ++i) f += T(t.projection(k, i)) * pf[i](c);
          r[t.fabric_features_offset + 3 * c + k] =
              t.fabric_features_w * (f - T(t.data_fabric_features(k, c)));
        }
    return true;
  }

  bool residuals(const double* z, double* r, FailureHint* hint) const override {
    EvalContext ctx = context(hint);
    return finish_values(eval(z, r, &ctx), z, r, &ctx, hint);
  }

  // Central differences: each of the 2p + 1 evaluations of a Jacobian counts as one. The
  // functor is the cost function's, one per fit: its hint is the fit's.
  struct NumericFunctor {
    const Kernel* k;
    mutable FailureHint hint;
    bool operator()(double const* const* z, double* r) const {
      return k->residuals(z[0], r, &hint);
    }
  };

  // The exact Jacobian by forward-mode Jets of 4 derivatives: the residuals evaluated once per
  // 4 free parameters (each pass takes the same substeps: the driver's control uses the values
  // only), as Ceres's DynamicAutoDiffCostFunction does and with its bits (the values of the
  // last pass), but each pass cut into its parts (the path, each envelope task) and the
  // passes x parts shared with a second thread while a core is free (cores.hpp): with
  // integrated predictions one Jacobian is milliseconds of Jets through the driver (~25 ms on
  // quick.toml), long enough for a thread of its own, and the start of a likelihood fit that
  // outlasts the other would otherwise leave the second core idle (docs/calibration.md
  // "Threads"). The values alone (Ceres's trial points) are cut into the same parts: with
  // integrated predictions they are ~20 ms of substeps on quick.toml. Rate predictions alone
  // take tens of microseconds, about a thread's start: those stay on the caller's thread.
  class JetCost final : public ceres::CostFunction {
   public:
    explicit JetCost(const Kernel* k) : k_(k) {
      set_num_residuals(k->o_->n_residuals);
      mutable_parameter_block_sizes()->push_back(k->o_->space.size());
    }
    bool Evaluate(double const* const* z, double* r, double** jac) const override {
      const int n = k_->o_->space.size(), m = k_->o_->n_residuals;
      const int parts = k_->parts();
      EvalContext ctx = k_->context(&hint_);
      if (jac == nullptr || jac[0] == nullptr) {
        // The values alone, part by part: a trial point of a fit with integrated predictions
        // is tens of milliseconds of substeps, worth the free core as much as a Jacobian is.
        const bool ok = share_units(
            parts, [&](int u) { return k_->run_part<double>(z[0], r, ctx.part(u), &ctx); });
        return k_->finish_values(ok, z[0], r, &ctx, &hint_);
      }
      using J = ceres::Jet<double, 4>;
      const int passes = (n + 3) / 4;
      std::vector<std::vector<J>> out(static_cast<std::size_t>(passes),
                                      std::vector<J>(static_cast<std::size_t>(m)));
      const auto seeded = [&](int pass) {
        std::vector<J> in(static_cast<std::size_t>(n));
        for (int i = 0; i < n; ++i) {
          in[i] = J(z[0][i]);
          if (i / 4 == pass) in[i].v[i % 4] = 1.0;
        }
        return in;
      };
      // Every pass of a part before the next part: the last failure's part first.
      const bool ok = share_units(passes * parts, [&](int u) {
        const int pass = u % passes, part = ctx.part(u / passes);
        const std::vector<J> in = seeded(pass);
        return k_->run_part<J>(in.data(), out[pass].data(), part, &ctx);
      });
      if (!ok)
        // A part run again: its first pass (every pass takes the same substeps).
        return k_->finish(false, r, &ctx, &hint_, [&](int part, EvalContext* alone) {
          const std::vector<J> in = seeded(0);
          std::vector<J> scratch(static_cast<std::size_t>(m));
          return k_->run_part<J>(in.data(), scratch.data(), part, alone);
        });
      for (int k = 0; k < m; ++k) {
        r[k] = out.back()[k].a;
        for (int j = 0; j < n; ++j) jac[0][k * n + j] = out[j / 4][k].v[j % 4];
      }
      return k_->o_->count(all_finite(r, m), false);
    }

   private:
    // unit(0) .. unit(units - 1), each independent, on the caller's thread and, where the
    // objective integrates and a core is free (cores.hpp), on a helper thread taking units
    // from the same counter; no unit starts after one has failed. false if any failed.
    template <class Unit>
    bool share_units(int units, const Unit& unit) const {
      std::atomic<int> next{0};
      std::atomic<bool> failed{false};
      auto work = [&] {
        for (int u = next++; u < units && !failed; u = next++)
          if (!unit(u)) failed = true;
      };
      if (units > 1 && k_->o_->any_integrated && cores::core_free()) {
        std::exception_ptr thrown;
        std::thread helper([&] {
          try {
            work();
          } catch (...) {
            failed = true;
            thrown = std::current_exception();
          }
        });
        try {
          work();
        } catch (...) {
          failed = true;
          helper.join();
          throw;
        }
        helper.join();
        if (thrown) std::rethrow_exception(thrown);
      } else {
        work();
      }
      return !failed;
    }

    const Kernel* k_;
    // This cost function's fit's stream of evaluations (Ceres evaluates one at a time).
    mutable FailureHint hint_;
  };

  ceres::CostFunction* cost_function() const override {
    const int n = o_->space.size();
    if (o_->options.derivatives == Derivatives::kExact) return new JetCost(this);
    ceres::NumericDiffOptions nd;
    // Relative step 1e-6 in z: the integrated objective is smooth to about the driver's
    // tolerance, so keep that tolerance far below 1e-6 when comparing against these.
    nd.relative_step_size = 1e-6;
    auto* f = new ceres::DynamicNumericDiffCostFunction<NumericFunctor, ceres::CENTRAL>(
        new NumericFunctor{this, {}}, ceres::TAKE_OWNERSHIP, nd);
    f->AddParameterBlock(n);
    f->SetNumResiduals(o_->n_residuals);
    return f;
  }

  bool envelope(const double* p, const StateData& s, const EnvelopeRecord& probes, bool integrated,
                EnvelopeRecord* out) const override {
    std::vector<Eigen::Vector2d> ps, pf;
    if (!predict<double>(p, p, s, probes, integrated, &ps, &pf)) return false;
    *out = model_record(probes, std::move(ps), std::move(pf));
    return true;
  }

  bool path(const double* p, PathData* out) const override {
    std::vector<models::MaterialState> states;
    if (!run_path<double>(p, p, &states)) return false;
    fill_path(states, o_->path, out);
    return true;
  }

  DriverLoad driver_load(const double* p) const override {
    DriverLoad load;
    load.limit = o_->options.step.max_substeps;
    const auto keep = [&load](const MostSubsteps& m, const std::string& where) {
      if (m.count <= load.substeps) return;
      load.substeps = m.count;
      load.where = where;
    };
    if (o_->path_task.active) {
      std::vector<models::MaterialState> states;
      MostSubsteps m;
      load.ok = run_path<double>(p, p, &states, &m) && load.ok;
      keep(m, "increment " + std::to_string(m.index) + " of " +
                  std::to_string(o_->path.eps_dev.size() - 1) + " of the path");
    }
    for (const EnvTask& t : o_->tasks) {
      if (!t.integrated) continue;
      std::vector<Eigen::Vector2d> ps, pf;
      MostSubsteps m;
      load.ok = predict<double>(p, p, o_->states[t.state], t.env, true, &ps, &pf, &m) && load.ok;
      if (m.index < 0) continue;
      const std::size_t i = static_cast<std::size_t>(m.index);
      keep(m, (i < t.env.theta_deg.size()
                   ? "the probe at theta = " + models::format_g(t.env.theta_deg[i]) + " deg"
                   : "probe " + std::to_string(i) + " of " + std::to_string(t.env.size())) +
                  " of state " + o_->states[t.state].label + "'s envelope " + t.env.name);
    }
    return load;
  }

 private:
  static models::MaterialState start_state(const double* pd, const Eigen::Matrix3d& stress,
                                           const Eigen::Matrix3d& fabric, double volume_fraction) {
    models::MaterialState st;
    st.stress = stress;
    st.fabric = fabric;
    st.volume_fraction = volume_fraction;
    st.internal = M::initial_internal(pd, stress, fabric);
    return st;
  }

  // A failed integration of a fit's evaluation (ctx) at probe `probe` of part `part`: false,
  // the other units stopped, and how the part ended kept for the evaluation's verdict
  // (finish).
  template <class Result>
  static bool failed(const Result& res, EvalContext* ctx, int part, int probe) {
    if (!ctx) return false;
    ctx->stop = true;
    PartEnd& e = ctx->end(part);
    e.probe = probe;
    e.on_limit = res.on_substep_limit;
    e.failed = true;
    return false;
  }

  // The prediction with the most substeps so far (driver_load): its count and index.
  struct MostSubsteps {
    int count = 0, index = -1;
    template <class Result>
    void see(const Result& res, int index_of) {
      if (res.attempted() <= count) return;
      count = res.attempted();
      index = index_of;
    }
  };

  template <typename T>
  bool predict(const T* p, const double* pd, const StateData& s, const EnvelopeRecord& env,
               bool integrated, std::vector<Eigen::Matrix<T, 2, 1>>* ps,
               std::vector<Eigen::Matrix<T, 2, 1>>* pf, MostSubsteps* most = nullptr,
               EvalContext* ctx = nullptr, int part = 0) const {
    const int m = env.size();
    ps->resize(m);
    pf->resize(m);
    const models::MaterialState sd = start_state(pd, s.stress, s.fabric, s.volume_fraction);
    if (!M::admissible(pd, sd, nullptr)) return false;
    const models::StateT<T> st = models::state_cast<T>(sd);
    if (integrated) {
      const models::StaticLawOps<M, T> ops{p, pd};
      // From the probe where this part failed last (each probe starts from the state).
      const int first = ctx && ctx->fail_part == part && m > 0 ? ctx->fail_probe % m : 0;
      for (int k = 0; k < m; ++k) {
        if (ctx && ctx->stop) return false;
        const int i = (first + k) % m;
        const auto res =
            models::integrate_adaptive(ops, st, env.strain_tensor(i), o_->options.step);
        if (most) most->see(res, i);
        if (!res.success) return failed(res, ctx, part, i);
        (*ps)[i] = pair_of<T>(models::Mat3<T>(res.end.stress - st.stress));
        (*pf)[i] = pair_of<T>(models::Mat3<T>(res.end.fabric - st.fabric));
      }
      return true;
    }
    for (int i = 0; i < m; ++i) {
      const models::RateT<T> rt =
          M::template rate<T>(p, st, env.strain_tensor(i).template cast<T>());
      (*ps)[i] = pair_of<T>(rt.d_stress);
      (*pf)[i] = pair_of<T>(rt.d_fabric);
    }
    return true;
  }

  // The law's path from the first data row, integrated from each sample of the data to the next
  // (the driver controls the error within each) along the data's strain increments, so that
  // the model is sampled exactly at the data's rows; one state per data row.
  template <typename T>
  bool run_path(const T* p, const double* pd, std::vector<models::StateT<T>>* states,
                MostSubsteps* most = nullptr, EvalContext* ctx = nullptr) const {
    const PathData& d = o_->path;
    const models::MaterialState sd = start_state(pd, d.stress[0], d.fabric[0], d.volume_fraction);
    if (!M::admissible(pd, sd, nullptr)) return false;
    const models::StaticLawOps<M, T> ops{p, pd};
    models::StateT<T> y = models::state_cast<T>(sd);
    states->assign(1, y);
    for (std::size_t k = 1; k < d.eps_dev.size(); ++k) {
      if (ctx && ctx->stop) return false;
      const auto res = models::integrate_adaptive(ops, y, d.increment(k), o_->options.step);
      if (most) most->see(res, static_cast<int>(k));
      if (!res.success) return failed(res, ctx, Objective::Impl::kPath, static_cast<int>(k));
      y = res.end;
      states->push_back(y);
    }
    return true;
  }

  // Path residuals: (iso, dev) pairs of stress and fabric at every data row after the
  // first (which the model starts from).
  template <typename T>
  bool path_residuals(const T* p, const double* pd, T* r, EvalContext* ctx) const {
    const PathData& d = o_->path;
    std::vector<models::StateT<T>> s;
    if (!run_path<T>(p, pd, &s, nullptr, ctx)) return false;
    const Eigen::Matrix<T, 2, 2> R = rendulic_to_iso_dev().cast<T>();
    const PathTask& t = o_->path_task;
    for (std::size_t k = 1; k < d.eps_dev.size(); ++k) {
      const Eigen::Matrix<T, 2, 1> ds =
          R * pair_of<T>(models::Mat3<T>(s[k].stress - d.stress[k].cast<T>()));
      const Eigen::Matrix<T, 2, 1> df =
          R * pair_of<T>(models::Mat3<T>(s[k].fabric - d.fabric[k].cast<T>()));
      const int i = 2 * (static_cast<int>(k) - 1);
      if (t.stress_offset >= 0) {
        r[t.stress_offset + i] = t.stress_w * ds(0);
        r[t.stress_offset + i + 1] = t.stress_w * ds(1);
      }
      if (t.fabric_offset >= 0) {
        r[t.fabric_offset + i] = t.fabric_w * df(0);
        r[t.fabric_offset + i + 1] = t.fabric_w * df(1);
      }
    }
    return true;
  }

  const Objective::Impl* o_;
};

// A UMAT (models/umat.hpp) is compiled elsewhere and cannot carry Jets: its residuals are
// computed in double, and its Jacobian by central differences with the UMAT driver's increments
// frozen at those of the residual evaluation (models::UmatSchedule), so that, as for the built-in
// laws' Jets, the derivative is that of the integrator with its accepted increments fixed and the
// differences see a smooth function rather than the driver's step-size decisions.
class UmatKernel final : public KernelBase {
 public:
  UmatKernel(const Objective::Impl* o, const models::UmatLaw& law) : o_(o), law_(law) {}

  // Residuals at z; `schedules` (if given) records the increments of every integration in
  // evaluation order, or, with `replay`, replays them.
  bool eval(const double* z, double* r, std::vector<models::UmatSchedule>* schedules, bool replay,
            std::atomic<bool>* on_limit) const {
    std::vector<double> p(o_->space.base().size());
    o_->space.full(z, p.data());
    const models::UmatLaw law = with(p.data());
    std::size_t next = 0;
    Schedules sc{schedules, replay, &next, on_limit};
    if (o_->path_task.active && !path_residuals(law, sc, r)) return false;
    for (const EnvTask& t : o_->tasks) {
      std::vector<Eigen::Vector2d> ps, pf;
      if (!predict(law, o_->states[t.state], t.env, t.integrated, sc, &ps, &pf)) return false;
      const int m = t.env.size();
      if (t.stress_offset >= 0)
        for (int i = 0; i < m; ++i)
          for (int c = 0; c < 2; ++c)
            r[t.stress_offset + 2 * i + c] = t.stress_w * (ps[i](c) - t.env.stress[i](c));
      if (t.features_offset >= 0)
        for (int c = 0; c < 2; ++c)
          for (int k = 0; k < 3; ++k) {
            double f = 0.0;
            for (int i = 0; i < m; ++i) f += t.projection(k, i) * ps[i](c);
            r[t.features_offset + 3 * c + k] = t.features_w * (f - t.data_features(k, c));
          }
    }
    return all_finite(r, o_->n_residuals);
  }

  // The UMAT's evaluations go part by part on one thread, from the first (no hint).
  bool residuals(const double* z, double* r, FailureHint*) const override {
    std::atomic<bool> on_limit{false};
    return o_->count(eval(z, r, nullptr, false, &on_limit), on_limit);
  }

  class Cost final : public ceres::CostFunction {
   public:
    explicit Cost(const UmatKernel* k) : k_(k) {
      mutable_parameter_block_sizes()->push_back(k->o_->space.size());
      set_num_residuals(k->o_->n_residuals);
    }
    bool Evaluate(double const* const* z, double* r, double** jac) const override {
      std::atomic<bool> on_limit{false};
      return k_->o_->count(evaluate(z, r, jac, &on_limit), on_limit);
    }

   private:
    bool evaluate(double const* const* z, double* r, double** jac,
                  std::atomic<bool>* on_limit) const {
      std::vector<models::UmatSchedule> schedules;
      if (!k_->eval(z[0], r, &schedules, false, on_limit)) return false;
      if (!jac || !jac[0]) return true;
      const int n = parameter_block_sizes()[0], m = num_residuals();
      std::vector<double> zz(z[0], z[0] + n), rp(m), rm(m);
      for (int j = 0; j < n; ++j) {
        // Relative step 1e-6 (as the built-in laws' numeric check): with the increments frozen
        // the truncation error is O(h^2) and the rounding error ~1e-10 of the residuals.
        const double h = 1e-6 * std::max(std::abs(zz[j]), 1.0);
        zz[j] = z[0][j] + h;
        if (!k_->eval(zz.data(), rp.data(), &schedules, true, on_limit)) return false;
        zz[j] = z[0][j] - h;
        if (!k_->eval(zz.data(), rm.data(), &schedules, true, on_limit)) return false;
        zz[j] = z[0][j];
        for (int i = 0; i < m; ++i) jac[0][i * n + j] = (rp[i] - rm[i]) / (2.0 * h);
      }
      return true;
    }

    const UmatKernel* k_;
  };

  ceres::CostFunction* cost_function() const override { return new Cost(this); }

  bool envelope(const double* p, const StateData& s, const EnvelopeRecord& probes, bool integrated,
                EnvelopeRecord* out) const override {
    std::vector<Eigen::Vector2d> ps, pf;
    std::size_t next = 0;
    if (!predict(with(p), s, probes, integrated, {nullptr, false, &next, nullptr}, &ps, &pf))
      return false;
    *out = model_record(probes, std::move(ps), std::move(pf));
    return true;
  }

  bool path(const double* p, PathData* out) const override {
    std::vector<models::MaterialState> states;
    std::size_t next = 0;
    if (!run_path(with(p), {nullptr, false, &next, nullptr}, &states)) return false;
    fill_path(states, o_->path, out);
    return true;
  }

 private:
  struct Schedules {
    std::vector<models::UmatSchedule>* all;
    bool replay;
    std::size_t* next;
    std::atomic<bool>* on_limit;  // set where an integration fails on the substep limit
    models::UmatSchedule* take() const {
      if (!all) return nullptr;
      if (!replay) {
        all->emplace_back();
        return &all->back();
      }
      if (*next >= all->size()) return nullptr;
      models::UmatSchedule* s = &(*all)[(*next)++];
      s->replay = true;
      return s;
    }
  };

  models::UmatLaw with(const double* p) const {
    models::UmatLaw law = law_;
    law.set_props_unchecked(std::vector<double>(p, p + o_->space.base().size()));
    return law;
  }

  // `state`: the label of the state probed (probe `index`, from 1), or nullptr on the path (step
  // `index`); named only when the integration fails, every evaluation integrates many times.
  bool integrate(const models::UmatLaw& law, const models::UmatState& y, const Eigen::Matrix3d& de,
                 const Schedules& sc, models::UmatState* end, const std::string* state,
                 std::size_t index) const {
    models::UmatSchedule* s = sc.take();
    // A replay must use the recorded increments: a missing schedule is a failed evaluation.
    if (sc.all && sc.replay && !s) return false;
    const models::StepResult res = law.integrate(y, de, o_->options.step, end, s);
    if (sc.on_limit && res.on_substep_limit) *sc.on_limit = true;
    if (!res.success)
      o_->note_failure((state ? "state '" + *state + "', probe " : std::string("path, step ")) +
                       std::to_string(index) + ": " + res.reason);
    return res.success;
  }

  bool predict(const models::UmatLaw& law, const StateData& s, const EnvelopeRecord& env,
               bool integrated, const Schedules& sc, std::vector<Eigen::Vector2d>* ps,
               std::vector<Eigen::Vector2d>* pf) const {
    const int m = env.size();
    ps->assign(m, Eigen::Vector2d::Zero());
    pf->assign(m, Eigen::Vector2d::Zero());
    const models::MaterialState st = law.make_state(s.stress, s.fabric, s.volume_fraction);
    const models::UmatState us = law.umat_state(st);
    for (int i = 0; i < m; ++i) {
      Eigen::Matrix3d ds;
      if (integrated) {
        models::UmatState end;
        if (!integrate(law, us, env.strain_tensor(i), sc, &end, &s.label, i + 1)) return false;
        ds = end.point.stress - st.stress;
      } else {
        models::LawRate r;
        if (!law.rate_checked(st, env.strain_tensor(i), &r, nullptr)) return false;
        ds = r.d_stress;
      }
      (*ps)[i] = rendulic_pair(ds);
    }
    return true;
  }

  bool run_path(const models::UmatLaw& law, const Schedules& sc,
                std::vector<models::MaterialState>* states) const {
    const PathData& d = o_->path;
    models::UmatState y =
        law.umat_state(law.make_state(d.stress[0], d.fabric[0], d.volume_fraction));
    states->assign(1, y.point);
    for (std::size_t k = 1; k < d.eps_dev.size(); ++k) {
      models::UmatState next;
      if (!integrate(law, y, d.increment(k), sc, &next, nullptr, k)) return false;
      y = std::move(next);
      states->push_back(y.point);
    }
    return true;
  }

  bool path_residuals(const models::UmatLaw& law, const Schedules& sc, double* r) const {
    const PathData& d = o_->path;
    std::vector<models::MaterialState> s;
    if (!run_path(law, sc, &s)) return false;
    const Eigen::Matrix2d R = rendulic_to_iso_dev();
    const PathTask& t = o_->path_task;
    for (std::size_t k = 1; k < d.eps_dev.size(); ++k) {
      const Eigen::Vector2d ds = R * rendulic_pair(Eigen::Matrix3d(s[k].stress - d.stress[k]));
      const int i = 2 * (static_cast<int>(k) - 1);
      if (t.stress_offset >= 0) {
        r[t.stress_offset + i] = t.stress_w * ds(0);
        r[t.stress_offset + i + 1] = t.stress_w * ds(1);
      }
    }
    return true;
  }

  const Objective::Impl* o_;
  models::UmatLaw law_;
};

double rms_norm(const std::vector<Eigen::Vector2d>& v) {
  double s = 0.0;
  for (const auto& x : v) s += x.squaredNorm();
  return v.empty() ? 0.0 : std::sqrt(s / v.size());
}

// The smallest noise we ascribe to data (relative to its scale): exact data (model-generated,
// or the linear response) would otherwise get infinite weight in the likelihood.
constexpr double kNoiseFloor = 1e-6;

// Robust noise of a sequence of residual pairs from their second differences: for data that
// are a smooth curve plus independent noise of standard deviation s per component, the second
// difference has standard deviation sqrt(6) s; its median absolute value (x 1.4826) ignores the
// few jumps and kinks a curve may have. Returned as the rms pair norm relative to `scale`.
double second_difference_noise(const std::vector<Eigen::Vector2d>& r, bool cyclic, double scale) {
  const int n = static_cast<int>(r.size());
  std::vector<double> d2;
  for (int i = cyclic ? 0 : 1; i < (cyclic ? n : n - 1); ++i) {
    const Eigen::Vector2d d = r[(i + 1) % n] - 2.0 * r[i] + r[(i + n - 1) % n];
    d2.push_back(std::abs(d(0)));
    d2.push_back(std::abs(d(1)));
  }
  if (d2.empty() || !(scale > 0.0)) return kNoiseFloor;
  std::nth_element(d2.begin(), d2.begin() + d2.size() / 2, d2.end());
  const double s = 1.4826 * d2[d2.size() / 2] / std::sqrt(6.0);
  return std::max(kSqrt2 * s / scale, kNoiseFloor);
}

// Noise of an envelope: of its residual from the affine (ellipse) fit c + M u(theta), taken
// around the circle of directions, so that the ellipse's own curvature does not count.
double envelope_noise(const std::vector<double>& theta, const std::vector<Eigen::Vector2d>& pairs,
                      double scale) {
  const int m = static_cast<int>(theta.size());
  std::vector<int> order(m);
  for (int i = 0; i < m; ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](int a, int b) { return theta[a] < theta[b]; });
  const Eigen::Matrix<double, 3, Eigen::Dynamic> P = affine_projection(theta);
  Eigen::Matrix<double, 3, 2> coef = Eigen::Matrix<double, 3, 2>::Zero();
  for (int i = 0; i < m; ++i) coef += P.col(i) * pairs[i].transpose();
  std::vector<Eigen::Vector2d> res;
  for (int i : order) {
    const double t = deg_to_rad(theta[i]);
    res.push_back(
        pairs[i] -
        (coef.row(0) + std::cos(t) * coef.row(1) + std::sin(t) * coef.row(2)).transpose());
  }
  return second_difference_noise(res, true, scale);
}

// Noise of the path: second differences of its (change of) pairs along eps_dev.
double path_noise(const std::vector<Eigen::Vector2d>& change, double scale) {
  return second_difference_noise(change, false, scale);
}

}  // namespace

// ---------------------------------------------------------------- Objective

Objective::Objective(std::string law_name, const CalibrationData& data,
                     const std::vector<std::string>& states, ParameterSpace space,
                     const ObjectiveOptions& options)
    : impl_(std::make_unique<Impl>(law_name, std::move(space), options)) {
  std::string why;
  if (!options.IsValid(&why)) throw InputError("calibration objective: " + why);
  Impl& o = *impl_;
  // A UMAT knows no fabric (models/umat.hpp).
  const bool umat = law_name == "umat";
  const bool law_fabric = !umat && detail::dispatch_law(law_name, [](auto tag) {
    return detail::kHasFabric<typename decltype(tag)::type>;
  });
  o.yield_surface = !umat && detail::dispatch_law(law_name, [](auto tag) {
    return models::kHasYieldSurface<typename decltype(tag)::type>;
  });
  int offset = 0;
  auto add_block = [&](const std::string& st, const std::string& kind, const std::string& env,
                       double amplitude, int size, double scale, double weight, bool integrated,
                       double noise) {
    ResidualBlock b;
    b.state = st;
    b.kind = kind;
    b.envelope = env;
    b.amplitude = amplitude;
    b.offset = offset;
    b.size = size;
    b.scale = scale;
    b.weight = weight;
    b.integrated = integrated;
    b.noise = noise;
    o.blocks.push_back(b);
    offset += size;
    return offset - size;
  };
  for (const auto& label : states) {
    const StateData* s = data.find(label);
    if (!s) throw InputError("calibration: no state '" + label + "' in the data");
    o.states.push_back(*s);
    const int si = static_cast<int>(o.states.size()) - 1;
    for (const auto& env : s->envelopes) {
      if (!is_valid_envelope(env, &why)) throw InputError("state '" + label + "': " + why);
      if (env.elastic() ? !options.elastic_envelopes : !options.plastic_envelopes) continue;
      // The linear response at a larger amplitude is the elastic one scaled: it repeats the
      // elastic block and carries no elasto-plastic information.
      if (options.linear_response_elastic_only && !env.elastic() && env.method == "linear_response")
        continue;
      EnvTask t;
      t.state = si;
      t.env = env;
      t.integrated = o.integrated(env);
      const int m = env.size();
      t.stress_scale = rms_norm(env.stress);
      if (!(t.stress_scale > 0.0))
        throw InputError("state '" + label + "' envelope '" + env.name +
                         "': all stress responses are zero");
      t.fabric_scale = env.has_fabric() ? rms_norm(env.fabric) : 0.0;
      bool used = false;
      if (options.envelope_points && options.weight_stress > 0.0) {
        t.stress_w = std::sqrt(options.weight_stress / m) / t.stress_scale;
        t.stress_offset = add_block(label, "stress", env.name, env.amplitude, 2 * m, t.stress_scale,
                                    options.weight_stress, t.integrated,
                                    envelope_noise(env.theta_deg, env.stress, t.stress_scale));
        used = true;
      }
      if (options.envelope_points && options.weight_fabric > 0.0 && law_fabric &&
          t.fabric_scale > options.fabric_scale_min) {
        t.fabric_w = std::sqrt(options.weight_fabric / m) / t.fabric_scale;
        t.fabric_offset = add_block(label, "fabric", env.name, env.amplitude, 2 * m, t.fabric_scale,
                                    options.weight_fabric, t.integrated,
                                    envelope_noise(env.theta_deg, env.fabric, t.fabric_scale));
        used = true;
      }
      if (options.envelope_features && options.weight_features > 0.0) {
        t.projection = affine_projection(env.theta_deg);
        for (int c = 0; c < 2; ++c)
          for (int k = 0; k < 3; ++k) {
            double f = 0.0;
            for (int i = 0; i < m; ++i) f += t.projection(k, i) * env.stress[i](c);
            t.data_features(k, c) = f;
          }
        t.features_w = std::sqrt(options.weight_features / 3.0) / t.stress_scale;
        t.features_offset = add_block(label, "features", env.name, env.amplitude, 6, t.stress_scale,
                                      options.weight_features, t.integrated,
                                      envelope_noise(env.theta_deg, env.stress, t.stress_scale));
        used = true;
        if (options.weight_fabric > 0.0 && law_fabric &&
            t.fabric_scale > options.fabric_scale_min) {
          for (int c = 0; c < 2; ++c)
            for (int k = 0; k < 3; ++k) {
              double f = 0.0;
              for (int i = 0; i < m; ++i) f += t.projection(k, i) * env.fabric[i](c);
              t.data_fabric_features(k, c) = f;
            }
          t.fabric_features_w =
              std::sqrt(options.weight_features * options.weight_fabric / 3.0) / t.fabric_scale;
          t.fabric_features_offset =
              add_block(label, "fabric_features", env.name, env.amplitude, 6, t.fabric_scale,
                        options.weight_features * options.weight_fabric, t.integrated,
                        envelope_noise(env.theta_deg, env.fabric, t.fabric_scale));
        }
      }
      if (used) {
        o.any_integrated = o.any_integrated || t.integrated;
        o.tasks.push_back(std::move(t));
      }
    }
  }
  if (options.path && !data.path.empty()) {
    o.path = data.path;
    const int n = static_cast<int>(o.path.eps_dev.size()) - 1;
    std::vector<Eigen::Vector2d> ds, df;
    for (int k = 1; k <= n; ++k) {
      ds.push_back(rendulic_pair(o.path.stress[k] - o.path.stress[0]));
      df.push_back(rendulic_pair(o.path.fabric[k] - o.path.fabric[0]));
    }
    // Scale: the rms change along the path (row 0 is matched by construction, so all the
    // information is in the change).
    const double ss = rms_norm(ds), sf = rms_norm(df);
    if (options.weight_path_stress > 0.0 && ss > 0.0) {
      o.path_task.stress_w = std::sqrt(options.weight_path_stress / n) / ss;
      o.path_task.stress_offset = add_block("path", "path_stress", "", 0.0, 2 * n, ss,
                                            options.weight_path_stress, true, path_noise(ds, ss));
    }
    if (options.weight_path_fabric > 0.0 && law_fabric && sf > options.fabric_scale_min) {
      o.path_task.fabric_w = std::sqrt(options.weight_path_fabric / n) / sf;
      o.path_task.fabric_offset = add_block("path", "path_fabric", "", 0.0, 2 * n, sf,
                                            options.weight_path_fabric, true, path_noise(df, sf));
    }
    o.path_task.active = o.path_task.stress_offset >= 0 || o.path_task.fabric_offset >= 0;
    o.any_integrated = o.any_integrated || o.path_task.active;
  }
  o.n_residuals = offset;
  if (o.n_residuals == 0) throw InputError("calibration: nothing to fit (no residual blocks)");
  if (o.space.size() == 0) throw InputError("calibration: no free parameters");
  if (umat) {
    const std::shared_ptr<const models::UmatLaw> u = models::session_umat();
    if (!u) throw InputError("calibration: model umat without a UMAT (--umat PATH.so)");
    if (o.space.base().size() != u->parameters().size())
      throw InputError("calibration: parameter vector does not match the UMAT's PROPS");
    o.kernel = std::make_unique<UmatKernel>(&o, *u);
    return;
  }
  o.kernel = detail::dispatch_law(law_name, [&](auto tag) -> std::unique_ptr<KernelBase> {
    using M = typename decltype(tag)::type;
    if (static_cast<int>(o.space.base().size()) != M::kCount)
      throw InputError("calibration: parameter vector does not match " + law_name);
    return std::make_unique<Kernel<M>>(&o);
  });
}

Objective::~Objective() = default;
Objective::Objective(Objective&&) noexcept = default;

const std::string& Objective::law_name() const { return impl_->law_name; }
const ParameterSpace& Objective::space() const { return impl_->space; }
const std::vector<ResidualBlock>& Objective::blocks() const { return impl_->blocks; }
int Objective::num_residuals() const { return impl_->n_residuals; }
int Objective::num_parameters() const { return impl_->space.size(); }
bool Objective::exact_derivatives() const {
  return impl_->options.derivatives == Derivatives::kExact && impl_->law_name != "umat";
}
bool Objective::integrated() const { return impl_->any_integrated; }

DriverLoad Objective::driver_load(const std::vector<double>& p) const {
  return impl_->kernel->driver_load(p.data());
}

std::string Objective::failure() const {
  std::lock_guard<std::mutex> lock(impl_->failure_mutex);
  return impl_->failure;
}

EvaluationTally Objective::tally() const {
  return {impl_->evaluations.load(), impl_->failed.load(), impl_->failed_on_limit.load()};
}

bool Objective::predict_path(const std::vector<double>& p, PathData* out) const {
  if (impl_->path.empty()) return false;
  return impl_->kernel->path(p.data(), out);
}

bool Objective::residuals(const double* z, double* r, FailureHint* hint) const {
  return impl_->kernel->residuals(z, r, hint);
}

ceres::CostFunction* Objective::make_cost_function() const {
  return impl_->kernel->cost_function();
}

bool Objective::jacobian(const double* z, Eigen::VectorXd* r, Eigen::MatrixXd* J) const {
  const int n = num_residuals(), p = num_parameters();
  std::unique_ptr<ceres::CostFunction> f(make_cost_function());
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> jr(n, p);
  r->resize(n);
  double* jac[1] = {jr.data()};
  const double* params[1] = {z};
  if (!f->Evaluate(params, r->data(), jac)) return false;
  *J = jr;
  return J->allFinite();
}

EnvelopeRecord Objective::predict_envelope(const std::vector<double>& p, const StateData& state,
                                           const EnvelopeRecord& probes, bool* ok) const {
  EnvelopeRecord out;
  *ok = impl_->kernel->envelope(p.data(), state, probes, impl_->integrated(probes), &out);
  return out;
}

std::vector<std::string> default_free_parameters(const std::string& law_name, int n_states,
                                                 bool has_path, bool has_plastic) {
  std::vector<std::string> f;
  const bool many = n_states >= 3;
  if (law_name == "isotropic_elastic") {
    f = {"K", "G", "c_F"};
    if (many) f.push_back("n_p");
  } else if (law_name == "anisotropic_elastic" || law_name == "elastoplastic_fabric") {
    f = {"B", "G", "beta_A", "c_F"};
    if (many) {
      f.push_back("n_p");
      f.push_back("a_G");
    }
    if (law_name == "elastoplastic_fabric" && (has_path || has_plastic)) {
      for (const char* n : {"m_e", "M_ss", "beta_s", "beta_F", "F_dev_max"}) f.push_back(n);
    }
  } else if (law_name == "hypoplastic_wu") {
    f = {"c1", "c2", "c3", "c4"};
  } else if (law_name == "umat") {
    // The props the parameters file gives search bounds (docs/umat.md).
    if (const auto u = models::session_umat())
      for (const auto& pi : u->parameter_info())
        if (std::isfinite(pi.lower) && std::isfinite(pi.upper)) f.push_back(pi.name);
    if (f.empty())
      throw InputError(
          "calibration of a UMAT: no free props (name them with --free, and give them bounds "
          "in the parameters file's [bounds] table)");
  } else {
    detail::dispatch_law(law_name, [](auto) { return 0; });  // throws the InputError
  }
  return f;
}

}  // namespace rendulic::calibration

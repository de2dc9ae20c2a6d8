// The calibration objective and its parameter space (objective.hpp; models.md "Calibration";
// the weighting and normalisation are documented in docs/calibration.md "Objectives").
#include "rendulic/calibration/objective.hpp"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <set>

#include "law_dispatch.hpp"
#include "rendulic/core/conventions.hpp"
#include "rendulic/core/errors.hpp"
#include "rendulic/models/paths.hpp"

namespace rendulic::calibration {

// ---------------------------------------------------------------- parameter space

ParameterSpace::ParameterSpace(const models::Law& law, const std::vector<double>& values,
                               const std::vector<std::string>& free,
                               const std::map<std::string, std::pair<double, double>>& bounds)
    : base_(values) {
  const auto& info = law.parameter_info();
  if (values.size() != info.size())
    throw InputError(std::string(law.name()) + " takes " + std::to_string(info.size()) +
                     " parameters, got " + std::to_string(values.size()));
  std::set<std::string> seen;
  for (const auto& name : free) {
    const int i = law.parameter_index(name);
    if (i < 0) throw InputError("unknown parameter '" + name + "' of " + std::string(law.name()));
    if (!seen.insert(name).second) throw InputError("parameter '" + name + "' listed twice");
    FreeParameter f;
    f.name = name;
    f.index = i;
    f.lower = info[i].lower;
    f.upper = info[i].upper;
    if (auto it = bounds.find(name); it != bounds.end()) {
      if (!(it->second.first < it->second.second) || it->second.first < info[i].lower ||
          it->second.second > info[i].upper)
        throw InputError("search bounds of '" + name + "' must lie within [" +
                         std::to_string(info[i].lower) + ", " + std::to_string(info[i].upper) +
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
    if (!seen.count(name)) throw InputError("search bounds given for '" + name + "', not free");
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
  if (path_steps < 10) return fail("path_steps must be >= 10");
  if (!(fabric_scale_min >= 0.0)) return fail("fabric_scale_min must be >= 0");
  return step.IsValid(why);
}

// ---------------------------------------------------------------- the kernel

namespace {

template <typename T>
Eigen::Matrix<T, 2, 1> pair_of(const models::Mat3<T>& q) {
  return {T(kSqrt2) * T(0.5) * (q(1, 1) + q(2, 2)), q(0, 0)};
}

template <typename T>
double value_of(const T& x) {
  if constexpr (std::is_same_v<T, double>) {
    return x;
  } else {
    return x.a;
  }
}

// Affine projection (probes/ fit_affine, written for any scalar): for directions theta_i the
// least-squares c + M u(theta) of points R_i is (U^T U)^-1 U^T R, U_i = (1, cos, sin).
Eigen::Matrix<double, 3, Eigen::Dynamic> affine_projection(const std::vector<double>& theta) {
  Eigen::MatrixXd U(theta.size(), 3);
  for (std::size_t i = 0; i < theta.size(); ++i) {
    const double t = deg_to_rad(theta[i]);
    U.row(i) << 1.0, std::cos(t), std::sin(t);
  }
  return (U.transpose() * U).ldlt().solve(U.transpose());
}

}  // namespace

struct EnvTask {
  int state = 0;  // index into Impl::states
  EnvelopeData env;
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
  virtual bool residuals(const double* z, double* r) const = 0;
  virtual ceres::CostFunction* cost_function() const = 0;
  virtual bool envelope(const double* p, const StateData& s, const EnvelopeData& probes,
                        bool integrated, EnvelopeData* out) const = 0;
};

struct Objective::Impl {
  std::string law_name;
  ParameterSpace space;
  ObjectiveOptions options;
  std::vector<StateData> states;
  PathData path;
  std::vector<EnvTask> tasks;
  PathTask path_task;
  std::vector<ResidualBlock> blocks;
  int n_residuals = 0;
  bool autodiff = false;
  std::unique_ptr<KernelBase> kernel;
};

namespace {

template <class M>
class Kernel final : public KernelBase {
 public:
  explicit Kernel(const Objective::Impl* o) : o_(o) {}

  // Residuals for any scalar; integrated blocks only for double (autodiff() is false then).
  template <typename T>
  bool eval(const T* z, T* r) const {
    T p[M::kCount];
    o_->space.full(z, p);
    double pd[M::kCount];
    for (int i = 0; i < M::kCount; ++i) pd[i] = value_of(p[i]);
    const int n_tasks = static_cast<int>(o_->tasks.size());
    bool ok = true;
    if constexpr (std::is_same_v<T, double>) {
      // Integrated laws (numeric Jacobians): every probe and the path is an independent
      // integration writing its own residuals, so tasks run in parallel, the path first (the
      // longest). The residuals do not depend on the thread count.
      const int n = n_tasks + (o_->path_task.active ? 1 : 0);
      int all = 1;
#pragma omp parallel for schedule(dynamic) reduction(min : all) if (n > 1 && !omp_in_parallel())
      for (int k = 0; k < n; ++k) {
        const bool path = o_->path_task.active && k == 0;
        const int t = o_->path_task.active ? k - 1 : k;
        all =
            std::min(all, (path ? path_residuals(pd, r) : task_residuals<T>(t, p, pd, r)) ? 1 : 0);
      }
      ok = all == 1;
    } else {
      for (int t = 0; t < n_tasks && ok; ++t) ok = task_residuals<T>(t, p, pd, r);
      if (ok && o_->path_task.active) return false;  // path: double only
    }
    if (!ok) return false;
    for (int i = 0; i < o_->n_residuals; ++i)
      if (!std::isfinite(value_of(r[i]))) return false;
    return true;
  }

  // Residuals of one envelope task.
  template <typename T>
  bool task_residuals(int index, const T* p, const double* pd, T* r) const {
    const EnvTask& t = o_->tasks[static_cast<std::size_t>(index)];
    std::vector<Eigen::Matrix<T, 2, 1>> ps, pf;
    {
      const StateData& s = o_->states[t.state];
      if (!predict<T>(p, pd, s, t.env, t.integrated, &ps, &pf)) return false;
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
    }
    return true;
  }

  bool residuals(const double* z, double* r) const override { return eval<double>(z, r); }

  struct AutoFunctor {
    const Kernel* k;
    template <typename T>
    bool operator()(T const* const* z, T* r) const {
      return k->eval<T>(z[0], r);
    }
  };
  struct NumericFunctor {
    const Kernel* k;
    bool operator()(double const* const* z, double* r) const { return k->eval<double>(z[0], r); }
  };

  ceres::CostFunction* cost_function() const override {
    const int n = o_->space.size();
    if (o_->autodiff) {
      // Stride 4: Jets of 4 derivatives, the law evaluated ceil(n/4) times per Jacobian.
      auto* f = new ceres::DynamicAutoDiffCostFunction<AutoFunctor, 4>(new AutoFunctor{this});
      f->AddParameterBlock(n);
      f->SetNumResiduals(o_->n_residuals);
      return f;
    }
    ceres::NumericDiffOptions nd;
    // Relative step 1e-6 in z: the integrated objective is smooth to ~1e-10 (driver tolerance),
    // so the central difference error is ~1e-4 relative at worst, ample for Gauss-Newton.
    nd.relative_step_size = 1e-6;
    auto* f = new ceres::DynamicNumericDiffCostFunction<NumericFunctor, ceres::CENTRAL>(
        new NumericFunctor{this}, ceres::TAKE_OWNERSHIP, nd);
    f->AddParameterBlock(n);
    f->SetNumResiduals(o_->n_residuals);
    return f;
  }

  bool envelope(const double* p, const StateData& s, const EnvelopeData& probes, bool integrated,
                EnvelopeData* out) const override {
    std::vector<Eigen::Vector2d> ps, pf;
    *out = probes;
    out->method = "model";
    if (!predict<double>(p, p, s, probes, integrated, &ps, &pf)) return false;
    out->stress = ps;
    out->fabric = pf;
    return true;
  }

 private:
  template <typename T>
  bool predict(const T* p, const double* pd, const StateData& s, const EnvelopeData& env,
               bool integrated, std::vector<Eigen::Matrix<T, 2, 1>>* ps,
               std::vector<Eigen::Matrix<T, 2, 1>>* pf) const {
    const int m = env.size();
    ps->resize(m);
    pf->resize(m);
    if (integrated) {
      if constexpr (std::is_same_v<T, double>) {
        const detail::ParamLaw<M> law(pd);
        const models::MaterialState st = law.make_state(s.stress, s.fabric, s.volume_fraction);
        if (!law.admissible(st, nullptr)) return false;
        for (int i = 0; i < m; ++i) {
          const models::StepResult res = models::integrate(law, st, env.d_eps[i], o_->options.step);
          if (!res.success) return false;
          (*ps)[i] = rendulic_pair(res.end.stress - st.stress);
          (*pf)[i] = rendulic_pair(res.end.fabric - st.fabric);
        }
        return true;
      } else {
        return false;
      }
    }
    models::StateT<T> st;
    st.stress = s.stress.template cast<T>();
    st.fabric = s.fabric.template cast<T>();
    st.internal = M::initial_internal(pd, s.stress, s.fabric).template cast<T>();
    st.volume_fraction = T(s.volume_fraction);
    {
      models::MaterialState sd;
      sd.stress = s.stress;
      sd.fabric = s.fabric;
      if (!M::admissible(pd, sd, nullptr)) return false;
    }
    for (int i = 0; i < m; ++i) {
      const models::RateT<T> rt = M::template rate<T>(p, st, env.d_eps[i].template cast<T>());
      (*ps)[i] = pair_of<T>(rt.d_stress);
      (*pf)[i] = pair_of<T>(rt.d_fabric);
    }
    return true;
  }

  // Undrained path from the first data row to the last eps_dev, sampled at the data's eps_dev.
  bool path_residuals(const double* pd, double* r) const {
    const PathData& d = o_->path;
    const detail::ParamLaw<M> law(pd);
    const models::MaterialState st = law.make_state(d.stress[0], d.fabric[0], d.volume_fraction);
    if (!law.admissible(st, nullptr)) return false;
    models::PathOptions po;
    po.steps = o_->options.path_steps;
    po.step = o_->options.step;
    const models::PathSeries s = models::undrained_axisymmetric_path(law, st, d.eps_dev.back(), po);
    if (!s.success) return false;
    const Eigen::Matrix2d R = rendulic_to_iso_dev();
    const int n = static_cast<int>(d.eps_dev.size());
    std::size_t j = 0;
    for (int k = 1; k < n; ++k) {
      const double e = std::abs(d.eps_dev[k]);
      while (j + 2 < s.eps_dev.size() && std::abs(s.eps_dev[j + 1]) < e) ++j;
      const double e0 = std::abs(s.eps_dev[j]), e1 = std::abs(s.eps_dev[j + 1]);
      const double w = e1 > e0 ? std::clamp((e - e0) / (e1 - e0), 0.0, 1.0) : 0.0;
      const Eigen::Matrix3d sig = (1 - w) * s.stress[j] + w * s.stress[j + 1];
      const Eigen::Matrix3d fab = (1 - w) * s.fabric[j] + w * s.fabric[j + 1];
      const PathTask& t = o_->path_task;
      const Eigen::Vector2d ds = R * rendulic_pair(sig - d.stress[k]);
      const Eigen::Vector2d df = R * rendulic_pair(fab - d.fabric[k]);
      if (t.stress_offset >= 0) {
        r[t.stress_offset + 2 * (k - 1)] = t.stress_w * ds(0);
        r[t.stress_offset + 2 * (k - 1) + 1] = t.stress_w * ds(1);
      }
      if (t.fabric_offset >= 0) {
        r[t.fabric_offset + 2 * (k - 1)] = t.fabric_w * df(0);
        r[t.fabric_offset + 2 * (k - 1) + 1] = t.fabric_w * df(1);
      }
    }
    return true;
  }

  const Objective::Impl* o_;
};

double rms_norm(const std::vector<Eigen::Vector2d>& v) {
  double s = 0.0;
  for (const auto& x : v) s += x.squaredNorm();
  return v.empty() ? 0.0 : std::sqrt(s / v.size());
}

}  // namespace

// ---------------------------------------------------------------- Objective

Objective::Objective(std::string law_name, const CalibrationData& data,
                     const std::vector<std::string>& states, ParameterSpace space,
                     const ObjectiveOptions& options)
    : impl_(std::make_unique<Impl>(
          Impl{law_name, std::move(space), options, {}, {}, {}, {}, {}, 0, false, nullptr})) {
  std::string why;
  if (!options.IsValid(&why)) throw InputError("calibration objective: " + why);
  Impl& o = *impl_;
  const bool law_fabric = detail::dispatch_law(
      law_name, [](auto tag) { return detail::kHasFabric<typename decltype(tag)::type>; });
  int offset = 0;
  auto add_block = [&](const std::string& st, const std::string& kind, const std::string& env,
                       int size, double scale, double weight, bool integrated) {
    o.blocks.push_back({st, kind, env, offset, size, scale, weight, integrated});
    offset += size;
    return offset - size;
  };
  bool all_rate = true;
  for (const auto& label : states) {
    const StateData* s = data.find(label);
    if (!s) throw InputError("calibration: no state '" + label + "' in the data");
    o.states.push_back(*s);
    const int si = static_cast<int>(o.states.size()) - 1;
    for (const auto& env : s->envelopes) {
      if (!env.IsValid(&why)) throw InputError("state '" + label + "': " + why);
      if (env.elastic() ? !options.elastic_envelopes : !options.plastic_envelopes) continue;
      EnvTask t;
      t.state = si;
      t.env = env;
      t.integrated = options.prediction == Prediction::kIntegrated ||
                     (options.prediction == Prediction::kAuto && !env.elastic());
      const int m = env.size();
      t.stress_scale = rms_norm(env.stress);
      if (!(t.stress_scale > 0.0))
        throw InputError("state '" + label + "' envelope '" + env.name +
                         "': all stress responses are zero");
      t.fabric_scale = env.has_fabric() ? rms_norm(env.fabric) : 0.0;
      bool used = false;
      if (options.envelope_points && options.weight_stress > 0.0) {
        t.stress_w = std::sqrt(options.weight_stress / m) / t.stress_scale;
        t.stress_offset = add_block(label, "stress", env.name, 2 * m, t.stress_scale,
                                    options.weight_stress, t.integrated);
        used = true;
      }
      if (options.envelope_points && options.weight_fabric > 0.0 && law_fabric &&
          t.fabric_scale > options.fabric_scale_min) {
        t.fabric_w = std::sqrt(options.weight_fabric / m) / t.fabric_scale;
        t.fabric_offset = add_block(label, "fabric", env.name, 2 * m, t.fabric_scale,
                                    options.weight_fabric, t.integrated);
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
        t.features_offset = add_block(label, "features", env.name, 6, t.stress_scale,
                                      options.weight_features, t.integrated);
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
              add_block(label, "fabric_features", env.name, 6, t.fabric_scale,
                        options.weight_features * options.weight_fabric, t.integrated);
        }
      }
      if (used) {
        all_rate = all_rate && !t.integrated;
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
      o.path_task.stress_offset =
          add_block("path", "path_stress", "", 2 * n, ss, options.weight_path_stress, true);
    }
    if (options.weight_path_fabric > 0.0 && law_fabric && sf > options.fabric_scale_min) {
      o.path_task.fabric_w = std::sqrt(options.weight_path_fabric / n) / sf;
      o.path_task.fabric_offset =
          add_block("path", "path_fabric", "", 2 * n, sf, options.weight_path_fabric, true);
    }
    o.path_task.active = o.path_task.stress_offset >= 0 || o.path_task.fabric_offset >= 0;
    all_rate = all_rate && !o.path_task.active;
  }
  o.n_residuals = offset;
  if (o.n_residuals == 0) throw InputError("calibration: nothing to fit (no residual blocks)");
  if (o.space.size() == 0) throw InputError("calibration: no free parameters");
  o.autodiff = all_rate;
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
bool Objective::autodiff() const { return impl_->autodiff; }

bool Objective::residuals(const double* z, double* r) const {
  return impl_->kernel->residuals(z, r);
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

EnvelopeData Objective::predict_envelope(const std::vector<double>& p, const StateData& state,
                                         const EnvelopeData& probes, bool* ok) const {
  EnvelopeData out;
  const bool integrated = impl_->options.prediction == Prediction::kIntegrated ||
                          (impl_->options.prediction == Prediction::kAuto && !probes.elastic());
  *ok = impl_->kernel->envelope(p.data(), state, probes, integrated, &out);
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
  } else {
    detail::dispatch_law(law_name, [](auto) { return 0; });  // throws the InputError
  }
  return f;
}

}  // namespace rendulic::calibration

// The speed-versus-accuracy sweep: preparation of the probed states, the
// points of each factor, their errors against the converged references, the Pareto front and
// the account of where each method breaks. See sweep.hpp; the findings are in docs/accuracy.md.
#include "sweep.hpp"

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <iomanip>
#include <limits>
#include <map>
#include <sstream>

#include "rendulic/core/comma_list.hpp"
#include "rendulic/core/conventions.hpp"
#include "rendulic/core/decimal.hpp"
#include "rendulic/core/errors.hpp"
#include "rendulic/core/option_table.hpp"
#include "rendulic/core/result_paths.hpp"
#include "rendulic/dem/contact.hpp"
#include "rendulic/dem/probe_campaign.hpp"
#include "rendulic/dem/scenario_keys.hpp"
#include "rendulic/probes/envelope_fit.hpp"

namespace rendulic::app {
namespace {

// Wall and CPU (all threads of the process) seconds since construction.
class Stopwatch {
 public:
  double wall() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0_).count();
  }
  double cpu() const { return static_cast<double>(std::clock() - cpu0_) / CLOCKS_PER_SEC; }

 private:
  std::chrono::steady_clock::time_point wall0_ = std::chrono::steady_clock::now();
  std::clock_t cpu0_ = std::clock();
};

std::string fmt(double x) {
  std::ostringstream s;
  s << std::setprecision(4) << x;
  return s.str();
}

// The scenario's protocol up to its first snapshot: gas, compression to nu0 and relaxation
// with the preparation damping, isotropic loading to nu_max and relaxation with the
// material's, the undrained path to the first states.eps_dev, brought to rest as by the states
// stage. The run's own sequence (dem/run_protocol.hpp) and options, with N replaced and one
// shortcut: the isotropic loading runs at its constant largest rate (isotropic.rate_max)
// instead of holding the inertial number. Held, it crawls through jamming at rate_min
// (minutes at N = 500); the probed state has the same nu, P* and eps_dev either way, and
// its preparation history is not what the sweep measures.
dem::DemSystem isotropic_state(const dem::DemRunOptions& o, int n, std::uint64_t seed) {
  dem::DemRunOptions on = o;
  on.gas.n_particles = static_cast<std::size_t>(n);
  dem::DemSystem sys = dem::prepare_packing(on, seed).system;
  dem::CompressOptions loading = o.loading;
  loading.inertial_number = 0.0;
  dem::load_isotropic(sys, loading, o.relax);
  dem::use_run_material(sys, o);
  return sys;
}

dem::DemSystem prepare_state(const dem::DemSystem& isotropic, const dem::DemRunOptions& o) {
  dem::DemSystem sys = isotropic;
  dem::PathOptions path = o.path;
  const double first =
      *std::min_element(path.snapshot_eps_dev.begin(), path.snapshot_eps_dev.end());
  path.eps_dev_max = first;
  path.snapshot_eps_dev = {first};
  path.samples = 2;
  dem::DemSystem state = std::move(dem::run_path(sys, path).snapshots.front());
  dem::bring_to_rest(state, o.state_rest);
  return state;
}

struct Features {
  double major = 0, minor = 0, inclination = 0;
  Eigen::Vector2d center = Eigen::Vector2d::Zero();
  std::string note;
};

// The fitted ellipse of the stress envelope (probes/envelope_fit.hpp, the fit the run stage
// uses, here without covariance or shape selection). Where the orthogonal-distance fit fails
// the least-squares Rendulic map gives the features, and the note says so.
Features stress_features(const dem::Envelope& env) {
  const Envelope e = envelope_of(env, Response::kStress);
  Features f;
  try {
    FitOptions fo;
    fo.shape = FitShape::kEllipse;
    fo.compute_covariance = false;
    const EnvelopeFit fit = fit_envelope(e, fo);
    f.major = fit.a;
    f.minor = fit.b;
    f.inclination = fit.inclination_deg.value_or(0.0);
    f.center = fit.center;
    if (fit.converged && std::isfinite(fit.a) && std::isfinite(fit.b)) return f;
    f.note = "ellipse fit did not converge; features from the least-squares map";
  } catch (const std::exception& ex) {
    f.note = std::string("ellipse fit failed (") + ex.what() + "); features from the map";
  }
  const dem::RendulicMap m = dem::fit_rendulic_map(env.strain, env.stress_star);
  f.major = m.semi_major;
  f.minor = m.semi_minor;
  f.inclination = m.inclination_deg;
  f.center = m.center;
  return f;
}

double angle_difference(double a, double b) {
  const double d = std::fmod(std::fabs(a - b), 180.0);
  return std::min(d, 180.0 - d);
}

// Error of an envelope against the reference of the same state and amplitude.
void compare(const dem::Envelope& env, const dem::Envelope& ref, const Features& ref_f,
             SweepPoint& p) {
  const Features f = stress_features(env);
  double max_d = 0, sum2 = 0;
  for (std::size_t k = 0; k < env.size(); ++k) {
    const double d = (env.stress_star[k] - ref.stress_star[k]).norm();
    max_d = std::max(max_d, d);
    sum2 += d * d;
  }
  const double a = ref_f.major;
  p.error = max_d / a;
  p.error_rms = std::sqrt(sum2 / static_cast<double>(env.size())) / a;
  p.major = f.major;
  p.minor = f.minor;
  p.inclination_deg = f.inclination;
  p.center_x = f.center.x();
  p.center_y = f.center.y();
  p.err_major = std::fabs(f.major - ref_f.major) / ref_f.major;
  p.err_minor = ref_f.minor > 0 ? std::fabs(f.minor - ref_f.minor) / ref_f.minor : 0.0;
  p.err_inclination_deg = angle_difference(f.inclination, ref_f.inclination);
  p.err_center = (f.center - ref_f.center).norm() / a;
  if (!f.note.empty()) p.note += (p.note.empty() ? "" : "; ") + f.note;
  p.theta_deg = env.theta_deg;
  for (const auto& s : env.stress_star) {
    p.stress_star_x.push_back(s.x());
    p.stress_star_y.push_back(s.y());
  }
  if (!std::isfinite(p.error) || !std::isfinite(p.major)) {
    p.status = "failed";
    p.note += (p.note.empty() ? "" : "; ") + std::string("non-finite envelope");
  }
}

double mean_of(const std::map<std::string, std::vector<double>>& diag, const std::string& key) {
  const auto it = diag.find(key);
  if (it == diag.end() || it->second.empty()) return 0.0;
  double s = 0;
  for (double x : it->second) s += x;
  return s / static_cast<double>(it->second.size());
}

// Whether the explicit scheme is stable for this state at this step: a copy at rest-ish runs
// a few thousand steps at fixed cell; an unstable step makes the energy grow exponentially
// (one would otherwise only notice at the probes' time cap, hundreds of thousands of steps
// later). Returns an empty string when stable, else what was seen.
std::string stability_probe(const dem::DemSystem& sys) {
  constexpr int kChecks = 10;      // x 200 steps: far beyond the growth time of a real
  constexpr double kGrowth = 1e3;  // instability, whose amplitude grows by a fixed factor
  dem::DemSystem s = sys;          // per step
  const double r0 = std::max(dem::relax_ratio(s), 1e-14);
  for (int c = 0; c < kChecks; ++c) {
    s.advance(200, Eigen::Vector3d::Zero());
    const double r = dem::relax_ratio(s);
    if (!std::isfinite(r) || r > kGrowth * r0) {
      return "kinetic/elastic energy grew from " + fmt(r0) + " to " + fmt(r) + " in " +
             std::to_string(200 * (c + 1)) + " steps at fixed cell";
    }
  }
  return {};
}

// Settings of one envelope.
struct Setting {
  std::string method;
  int n = 0;
  double dt_factor = 0, inertial_number = 0, relax = 0, amplitude = 0;
  std::string key() const {
    std::ostringstream s;
    s << method << '|' << n << '|' << dt_factor << '|' << inertial_number << '|' << relax << '|'
      << amplitude;
    return s.str();
  }
};

struct StateData {
  dem::DemSystem system;
  dem::Envelope elastic_ref;  // linear response
  Features elastic_f;
  dem::Envelope plastic_ref;  // minimisation (made on first use)
  Features plastic_f;
  bool has_plastic = false;
};

class Sweeper {
 public:
  Sweeper(const Scenario& sc, const SweepOptions& o, const SweepProgress& progress)
      : sc_(sc), o_(o), progress_(progress) {
    run_ = dem::dem_options_from_scenario(sc);
    probe_ = dem::probe_options_from(sc);
    probe_.threads = o.threads;
    if (o.directions > 0) probe_.directions = o.directions;
    o_.directions = probe_.directions;
    theta_ = dem::probe_directions(probe_.directions);
    const auto& amps = probe_.amplitudes;
    elastic_amp_ = *std::min_element(amps.begin(), amps.end());
    plastic_amp_ = *std::max_element(amps.begin(), amps.end());
    if (!is_elastic_amplitude(elastic_amp_))
      throw InputError("sweep: probes.amplitudes needs an elastic amplitude (< " +
                       fmt(kElasticAmplitudeMax) + ")");
    seed_ = static_cast<std::uint64_t>(sc.get_int("run.seed"));
  }

  SweepSummary run() {
    Stopwatch total;
    SweepSummary s;
    s.options = o_;
    s.scenario_toml = sc_.to_toml();
    s.elastic_amplitude = elastic_amp_;
    s.plastic_amplitude = is_plastic_amplitude(plastic_amp_) ? plastic_amp_ : 0.0;
    s.stability_limit_factor =
        dem::stability_limit(run_.system.material) / dem::time_step(run_.system.material, 1.0);
    const Setting base{"dynamic",
                       o_.base_n,
                       run_.system.dt_factor,
                       probe_.inertial_number,
                       probe_.relax.kinetic_to_elastic,
                       elastic_amp_};
    for (const std::string& factor : o_.factors) {
      if (factor == "dt_factor") {
        for (double v : o_.dt_factors)
          add(s, factor, v, with(base, [&](Setting& x) { x.dt_factor = v; }));
      } else if (factor == "n_particles") {
        for (double v : o_.n_particles)
          add(s, factor, v, with(base, [&](Setting& x) { x.n = static_cast<int>(v); }));
      } else if (factor == "inertial_number") {
        for (double amp : {elastic_amp_, plastic_amp_}) {
          if (amp == plastic_amp_ && s.plastic_amplitude == 0) continue;
          for (double v : o_.inertial_numbers)
            add(s, factor, v, with(base, [&](Setting& x) {
                  x.inertial_number = v;
                  x.amplitude = amp;
                }));
        }
      } else if (factor == "relax") {
        for (double v : o_.relax_thresholds)
          add(s, factor, v, with(base, [&](Setting& x) { x.relax = v; }));
      } else if (factor == "dt_factor_tight") {
        for (double v : o_.dt_factors)
          add(s, factor, v, with(base, [&](Setting& x) {
                x.dt_factor = v;
                x.relax = o_.tight_relax;
              }));
      } else if (factor == "path_rate") {
        for (double v : o_.path_rates) s.path_points.push_back(path_point(v));
      } else if (factor == "method") {
        for (const std::string& m : o_.methods) {
          add(s, factor, 0.0, with(base, [&](Setting& x) { x.method = m; }));
          if (s.plastic_amplitude > 0)
            add(s, factor, 0.0, with(base, [&](Setting& x) {
                  x.method = m;
                  x.amplitude = plastic_amp_;
                }));
        }
      }
    }
    std::stable_sort(
        s.path_points.begin(), s.path_points.end(),
        [](const PathRatePoint& a, const PathRatePoint& b) { return a.rate > b.rate; });
    compare_path_rates(s.path_points, o_.path_rate_target);
    for (const auto& [n, st] : states_) s.states.push_back(state_summary_[n]);
    mark_pareto(s.points);
    describe_breaks(s);
    s.wall_s = total.wall();
    s.cpu_s = total.cpu();
    return s;
  }

 private:
  template <class F>
  static Setting with(Setting s, F f) {
    f(s);
    return s;
  }

  void say(const std::string& line) const {
    if (progress_) progress_(line);
  }

  StateData& state(int n) {
    auto it = states_.find(n);
    if (it != states_.end()) return it->second;
    say("preparing the state at N = " + std::to_string(n) + " ...");
    Stopwatch w;
    dem::DemSystem sys = prepare_state(isotropic(n, seed_), run_);
    SweepState ss;
    ss.n_particles = n;
    ss.prepare_wall_s = w.wall();
    ss.prepare_cpu_s = w.cpu();
    const dem::Measures m = sys.measure();
    ss.volume_fraction = m.volume_fraction;
    ss.pressure_star = m.pressure_star;
    ss.eps_dev = m.eps_dev;
    ss.coordination = m.coordination;
    dem::Envelope ref = dem::linear_response_envelope(sys, elastic_amp_, theta_, probe_);
    const Features f = stress_features(ref);
    ss.ref_major = f.major;
    ss.ref_minor = f.minor;
    ss.ref_inclination_deg = f.inclination;
    state_summary_[n] = ss;
    return states_.emplace(n, StateData{std::move(sys), std::move(ref), f, {}, {}, false})
        .first->second;
  }

  // The isotropic state at nu_max of N particles from a seed (made once).
  const dem::DemSystem& isotropic(int n, std::uint64_t seed) {
    const auto key = std::make_pair(n, seed);
    auto it = isotropic_.find(key);
    if (it == isotropic_.end()) it = isotropic_.emplace(key, isotropic_state(run_, n, seed)).first;
    return it->second;
  }

  // The path at `rate` from the isotropic state of each of path_seeds seeds (run.seed,
  // run.seed + 1, ...): the steady-state mean per seed, and over the seeds.
  PathRatePoint path_point(double rate) {
    PathRatePoint p;
    p.rate = rate;
    try {
      std::vector<double> inertial_means;
      for (int k = 0; k < o_.path_seeds; ++k) {
        dem::DemSystem sys = isotropic(o_.base_n, seed_ + static_cast<std::uint64_t>(k));
        dem::PathOptions path = run_.path;
        path.rate = rate;
        path.snapshot_eps_dev.clear();
        std::vector<double> x, ratio, inertial;
        Stopwatch w;
        const dem::PathSummary run = dem::run_path(sys, path, [&](const dem::Measures& m) {
          if (!(m.pressure > 0)) return;
          x.push_back(std::abs(m.eps_dev));
          ratio.push_back(std::abs(signed_deviator(m.stress)) / m.pressure);
          inertial.push_back(m.inertial_number);
        });
        p.wall_s += w.wall();
        p.cpu_s += w.cpu();
        p.steps += run.steps;
        const double lo = dem::kSteadyStateFrom * path.eps_dev_max, hi = path.eps_dev_max;
        const dem::WindowMean r = dem::window_mean(x, ratio, lo, hi);
        if (!r.ok) {
          p.status = "failed";
          p.note = "too few samples in the steady-state window (" + std::to_string(r.samples) +
                   "): raise path.samples";
          break;
        }
        p.ratio_per_seed.push_back(r.mean);
        p.ratio_stderr_per_seed.push_back(r.standard_error);
        p.window_samples = r.samples;
        inertial_means.push_back(dem::window_mean(x, inertial, lo, hi).mean);
      }
      if (p.status == "ok") {
        const auto n = static_cast<double>(p.ratio_per_seed.size());
        for (std::size_t k = 0; k < p.ratio_per_seed.size(); ++k) {
          p.ratio += p.ratio_per_seed[k] / n;
          p.inertial_number += inertial_means[k] / n;
        }
        // Independent seeds: the spread of their means; one seed: its batch-means error.
        if (p.ratio_per_seed.size() >= 2) {
          double ss = 0;
          for (double v : p.ratio_per_seed) ss += (v - p.ratio) * (v - p.ratio);
          p.ratio_stderr = std::sqrt(ss / (n - 1) / n);
        } else {
          p.ratio_stderr = p.ratio_stderr_per_seed.front();
        }
      }
    } catch (const std::exception& e) {
      p.status = "failed";
      p.note = std::string("failed: ") + e.what();
    }
    say("path_rate = " + fmt(rate) + ": " +
        (p.status == "ok"
             ? "|sigma_dev|/P " + fmt(p.ratio) + " +- " + fmt(p.ratio_stderr) +
                   " at I = " + fmt(p.inertial_number) + " (" +
                   std::to_string(p.ratio_per_seed.size()) + " seeds), cpu " + fmt(p.cpu_s) + " s"
             : p.note));
    return p;
  }

  const std::pair<const dem::Envelope*, const Features*> reference(StateData& st, double amp) {
    if (amp == elastic_amp_) return {&st.elastic_ref, &st.elastic_f};
    if (!st.has_plastic) {
      st.plastic_ref = dem::minimisation_envelope(st.system, amp, theta_, probe_);
      st.plastic_f = stress_features(st.plastic_ref);
      st.has_plastic = true;
    }
    return {&st.plastic_ref, &st.plastic_f};
  }

  void add(SweepSummary& s, const std::string& factor, double value, const Setting& x) {
    SweepPoint p;
    const auto hit = cache_.find(x.key());
    if (hit != cache_.end()) {
      p = hit->second;
      p.note += (p.note.empty() ? "" : "; ") + std::string("same setting as an earlier point");
    } else {
      p = evaluate(x);
      cache_[x.key()] = p;
    }
    p.factor = factor;
    p.value = factor == "method" ? 0.0 : value;
    p.meets_target = p.status == "ok" && p.error <= o_.target;
    say(factor + " = " + (factor == "method" ? x.method : fmt(value)) + " (" + p.method + ", " +
        p.envelope + "): " +
        (p.status == "ok" ? "error " + fmt(p.error) + ", cpu " + fmt(p.cpu_s) + " s" : p.note));
    s.points.push_back(std::move(p));
  }

  SweepPoint evaluate(const Setting& x) {
    SweepPoint p;
    p.method = x.method;
    p.envelope = x.amplitude == elastic_amp_ ? "elastic" : "plastic";
    p.n_particles = x.n;
    p.dt_factor = x.dt_factor;
    p.inertial_number = x.inertial_number;
    p.relax = x.relax;
    p.amplitude = x.amplitude;
    dem::SystemOptions so = run_.system;
    so.dt_factor = x.dt_factor;
    try {
      dem::check_time_step(so.material, x.dt_factor, "dem.dt_factor");
    } catch (const InputError& e) {
      p.status = "refused";
      p.note = std::string("refused: beyond stability (") + e.what() + ")";
      return p;
    }
    StateData& st = state(x.n);
    const auto [ref, ref_f] = reference(st, x.amplitude);
    dem::ProbeOptions po = probe_;
    po.inertial_number = x.inertial_number;
    po.rate = 0.0;  // the inertial number sets the rate
    po.relax.kinetic_to_elastic = x.relax;
    // The sweep's `relax` factor is the seed's relaxation threshold, which the FIRE tail (the
    // default, docs/accuracy.md "FIRE for the relaxation tail") does not use: the sweep measures
    // the seed's relaxation throughout, as its tables were made.
    po.relax_method = "dynamic";
    try {
      dem::Envelope env;
      Stopwatch w;
      if (x.method == "dynamic") {
        const dem::DemSystem sys = x.dt_factor == st.system.options().dt_factor
                                       ? st.system
                                       : dem::DemSystem::restore(st.system.save(), so);
        const std::string unstable = stability_probe(sys);
        if (!unstable.empty()) {
          p.status = "diverged";
          p.note = "diverged: " + unstable;
          return p;
        }
        env = dem::dynamic_envelope(sys, x.amplitude, theta_, po);
        p.converged_fraction = mean_of(env.diagnostics, "relax_converged");
        p.steps_per_probe =
            mean_of(env.diagnostics, "load_steps") + mean_of(env.diagnostics, "relax_steps");
        p.inertial_number = env.attributes["inertial_number"];
        p.reference_relax_steps = env.attributes["reference_relax_steps"];
      } else if (x.method == "minimisation") {
        env = dem::minimisation_envelope(st.system, x.amplitude, theta_, po);
        p.converged_fraction = mean_of(env.diagnostics, "converged");
      } else {
        env = dem::linear_response_envelope(st.system, x.amplitude, theta_, po);
      }
      p.wall_s = w.wall();
      p.cpu_s = w.cpu();
      compare(env, *ref, *ref_f, p);
      if (p.converged_fraction < 1.0)
        p.note += (p.note.empty() ? "" : "; ") + fmt(100 * (1 - p.converged_fraction)) +
                  " % of the probes hit their cap";
    } catch (const std::exception& e) {
      const std::string what = e.what();
      p.status = what.find("diverged") != std::string::npos ? "diverged" : "failed";
      p.note = p.status + ": " + what;
    }
    return p;
  }

  const Scenario& sc_;
  SweepOptions o_;
  SweepProgress progress_;
  dem::DemRunOptions run_;
  dem::ProbeOptions probe_;
  std::vector<double> theta_;
  double elastic_amp_ = 0, plastic_amp_ = 0;
  std::uint64_t seed_ = 1;
  std::map<int, StateData> states_;
  std::map<std::pair<int, std::uint64_t>, dem::DemSystem> isotropic_;
  std::map<int, SweepState> state_summary_;
  std::map<std::string, SweepPoint> cache_;
};

bool all_positive(const std::vector<double>& v) {
  return std::all_of(v.begin(), v.end(), [](double x) { return x > 0 && std::isfinite(x); });
}

// The points of one factor and envelope with status ok, by increasing value.
std::vector<const SweepPoint*> ok_points(const SweepSummary& s, const std::string& factor,
                                         const std::string& envelope = "elastic") {
  std::vector<const SweepPoint*> out;
  for (const SweepPoint& p : s.points)
    if (p.factor == factor && p.status == "ok" && p.envelope == envelope) out.push_back(&p);
  std::sort(out.begin(), out.end(),
            [](const SweepPoint* a, const SweepPoint* b) { return a->value < b->value; });
  return out;
}

}  // namespace

SweepOptions SweepOptions::preset(bool quick) {
  SweepOptions o;
  o.quick = quick;
  if (quick) {
    o.base_n = 250;
    o.directions = 8;
    o.dt_factors = {0.01, 0.02, 0.05, 0.1, 0.2};
    o.n_particles = {250, 500};
    o.inertial_numbers = {1e-4, 1e-3, 1e-2};
    o.relax_thresholds = {1e-4, 1e-5, 1e-6, 1e-7, 1e-8};
    o.path_rates = {4000, 1000};
  } else {
    o.base_n = 1000;
    o.directions = 0;  // the scenario's probes.directions
    o.dt_factors = {0.005, 0.01, 0.02, 0.05, 0.1, 0.15, 0.18, 0.2, 0.3};
    o.n_particles = {250, 500, 1000, 2000};
    o.inertial_numbers = {1e-5, 1e-4, 3e-4, 1e-3, 3e-3, 1e-2};
    o.relax_thresholds = {1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11};
    o.path_rates = {1200, 600, 300, 150, 75, 37.5};
  }
  return o;
}

bool SweepOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& m) {
    if (why) *why = m;
    return false;
  };
  if (factors.empty()) return fail("sweep: no factor to sweep");
  for (const auto& f : factors)
    if (std::find(kSweepFactors.begin(), kSweepFactors.end(), f) == kSweepFactors.end()) {
      return fail("sweep: unknown factor '" + f + "' (" + comma_list(kSweepFactors) + ")");
    }
  // Listed twice, a factor was swept twice: the same runs again and twice the rows.
  if (const std::string* again = first_repeat(factors))
    return fail("sweep: factor '" + *again + "' listed twice");
  if (threads < 0) return fail("sweep: threads must be >= 0");
  if (!(target > 0 && target < 1)) return fail("sweep: target must be in (0, 1)");
  if (base_n < 50) return fail("sweep: base N must be >= 50");
  if (directions != 0 && directions < 4) return fail("sweep: directions must be 0 or >= 4");
  if (!all_positive(dt_factors) || !all_positive(n_particles) || !all_positive(inertial_numbers) ||
      !all_positive(relax_thresholds) || !all_positive(path_rates))
    return fail("sweep: every swept value must be positive and finite");
  for (double n : n_particles)
    if (n < 50 || n != std::floor(n)) return fail("sweep: N values must be integers >= 50");
  for (double i : inertial_numbers)
    if (i > 1e-2) return fail("sweep: inertial numbers must be <= 1e-2 (probes.inertial_number)");
  for (double r : relax_thresholds)
    if (r >= 1) return fail("sweep: relaxation thresholds must be < 1");
  if (!(tight_relax > 0 && tight_relax < 1)) return fail("sweep: tight_relax must be in (0, 1)");
  if (!(path_rate_target > 0 && path_rate_target < 1))
    return fail("sweep: path_rate_target must be in (0, 1)");
  if (path_seeds < 1 || path_seeds > 64) return fail("sweep: path seeds must be in 1..64");
  // --path-rates 400,400 ran the same packings at the same rate twice, and wrote twice the rows.
  std::vector<double> rates = path_rates;
  std::sort(rates.begin(), rates.end());
  if (const auto again = std::adjacent_find(rates.begin(), rates.end()); again != rates.end())
    return fail("sweep: path rate " + decimal_g(*again) + " listed twice");
  for (const auto& m : methods)
    if (const std::string why = choice_refusal(m, kProbeMethods); !why.empty())
      return fail("sweep: method " + why);
  return true;
}

void check_sweep_inputs(const Scenario& scenario, const SweepOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) throw InputError(why);
  // Swept values stand for scenario keys and are held to their ranges: --path-rates 1e308 ran,
  // 'ok', with an inertial number of inf written to sweep.h5.
  Scenario held = scenario;
  for (double rate : options.path_rates) try {
      held.set("path.rate", rate);
    } catch (const InputError& e) {
      throw InputError(std::string("sweep --path-rates: ") + e.what());
    }
  const Sweeper check(scenario, options, {});  // its constructor checks the scenario's keys
  (void)check;
}

SweepSummary run_sweep(const Scenario& scenario, const SweepOptions& options,
                       const SweepProgress& progress) {
  std::string why;
  if (!options.IsValid(&why)) throw InputError(why);
  Sweeper sweeper(scenario, options, progress);
  return sweeper.run();
}

void mark_pareto(std::vector<SweepPoint>& points) {
  // The linear response is the elastic reference (error 0 by definition): it would dominate
  // everything and say nothing about the settings of the methods measured against it.
  auto eligible = [](const SweepPoint& p) {
    return p.status == "ok" && p.envelope == "elastic" && p.method != "linear_response";
  };
  for (SweepPoint& p : points) {
    p.pareto = false;
    if (!eligible(p)) continue;
    bool dominated = false;
    for (const SweepPoint& q : points) {
      if (&q == &p || !eligible(q)) continue;
      if (q.cpu_s <= p.cpu_s && q.error <= p.error && (q.cpu_s < p.cpu_s || q.error < p.error)) {
        dominated = true;
        break;
      }
    }
    p.pareto = !dominated;
  }
}

void compare_path_rates(std::vector<PathRatePoint>& points, double target) {
  for (PathRatePoint& p : points) {
    p.has_slower = false;
    p.converged = false;
    if (p.status != "ok") continue;
    for (const PathRatePoint& q : points) {
      if (q.status != "ok" || std::abs(q.rate * 4.0 - p.rate) > 1e-9 * p.rate) continue;
      p.has_slower = true;
      p.change_4x = std::abs(p.ratio - q.ratio) / q.ratio;
      p.converged = p.change_4x <= target;
    }
  }
}

void describe_breaks(SweepSummary& s) {
  s.breaks.clear();
  s.recommendations.clear();
  const double target = s.options.target;
  // Refused and diverged settings, whatever the factor.
  for (const SweepPoint& p : s.points) {
    if (p.status == "refused" || p.status == "diverged" || p.status == "failed")
      s.breaks.push_back(p.factor + " = " + fmt(p.value) + " (" + p.method + "): " + p.note);
  }
  // The time step: the largest accepted factor and what it costs in accuracy.
  for (const std::string factor : {"dt_factor", "dt_factor_tight"}) {
    const auto dt = ok_points(s, factor);
    if (dt.empty()) continue;
    const SweepPoint* top = dt.back();
    s.breaks.push_back(factor + ": largest accepted " + fmt(top->value) + " (bound " +
                       fmt(s.stability_limit_factor) + " t_c) gives error " + fmt(top->error) +
                       (top->meets_target ? " (meets the target)" : " (misses the target)") +
                       " against " + fmt(dt.front()->error) + " at " + fmt(dt.front()->value));
  }
  // The relaxation threshold: the noise floor below which tightening buys nothing.
  if (const auto rx = ok_points(s, "relax"); rx.size() >= 2) {
    double floor = std::numeric_limits<double>::infinity();
    for (const SweepPoint* p : rx) floor = std::min(floor, p->error);
    // Within 25 % of the best error (or 0.1 % of a_ref) counts as on the floor: the floor is
    // set by what relaxation cannot remove (the finite amplitude, contact changes).
    const double tol = std::max(1.25 * floor, floor + 1e-3);
    const SweepPoint* loosest = nullptr;
    for (auto it = rx.rbegin(); it != rx.rend(); ++it)
      if ((*it)->error <= tol) {
        loosest = *it;
        break;
      }
    if (loosest == rx.front())
      s.breaks.push_back(
          "relax: no noise floor reached: the error still falls at the tightest "
          "threshold " +
          fmt(loosest->value) + " (error " + fmt(floor) + ", cpu " + fmt(loosest->cpu_s) +
          " s); looser ones: error up to " + fmt(rx.back()->error));
    else if (loosest)
      s.breaks.push_back("relax: noise floor error " + fmt(floor) + " reached at threshold " +
                         fmt(loosest->value) + " (cpu " + fmt(loosest->cpu_s) +
                         " s); tighter thresholds cost up to " + fmt(rx.front()->cpu_s) +
                         " s for no gain; looser ones: error up to " + fmt(rx.back()->error));
  }
  // The loading rate: where the error leaves its quasi-static value.
  for (const std::string envelope : {"elastic", "plastic"}) {
    const auto in = ok_points(s, "inertial_number", envelope);
    if (in.size() < 2) continue;
    const double qs = in.front()->error;
    const SweepPoint* onset = nullptr;
    for (const SweepPoint* p : in)
      if (p->error > std::max(2.0 * qs, qs + 0.5 * target)) {
        onset = p;
        break;
      }
    const std::string head = "inertial_number (" + envelope + "): ";
    s.breaks.push_back(onset ? head + "rate effect from I = " + fmt(onset->value) + " (error " +
                                   fmt(onset->error) + " against " + fmt(qs) +
                                   " at I = " + fmt(in.front()->value) + ")"
                             : head + "no rate effect up to I = " + fmt(in.back()->value) +
                                   " (error " + fmt(in.back()->error) + ")");
  }
  // N: the spread of the exact reference itself with the packing size (one seed each).
  if (s.states.size() >= 2) {
    const SweepState& big = s.states.back();
    std::ostringstream line;
    line << "n_particles: linear-response major axis relative to N = " << big.n_particles << ":";
    for (const SweepState& st : s.states)
      line << " N " << st.n_particles << " " << fmt(st.ref_major / big.ref_major - 1.0);
    line << " (one packing per N: size effect and sample-to-sample spread together)";
    s.breaks.push_back(line.str());
  }
  // Methods at the elasto-plastic amplitude: the linear response has no plasticity.
  for (const SweepPoint& p : s.points)
    if (p.factor == "method" && p.envelope == "plastic" && p.status == "ok" &&
        p.method != "minimisation")
      s.breaks.push_back("method " + p.method + " at amplitude " + fmt(p.amplitude) + ": error " +
                         fmt(p.error) + " against the minimisation envelope");
  // The path's rate: the steady-state ratio against the run 4x slower.
  for (const PathRatePoint& p : s.path_points) {
    if (p.status != "ok") {
      s.breaks.push_back("path_rate = " + fmt(p.rate) + ": " + p.note);
    } else if (p.has_slower) {
      s.breaks.push_back("path_rate = " + fmt(p.rate) + " (I = " + fmt(p.inertial_number) +
                         "): steady-state |sigma_dev|/P " + fmt(p.ratio) + " +- " +
                         fmt(p.ratio_stderr) + ", " + fmt(100 * p.change_4x) +
                         " % from the run 4x slower" +
                         (p.converged ? " (quasi-static)" : " (rate-dependent)"));
    }
  }
  if (!s.path_points.empty()) {
    const PathRatePoint* best = nullptr;
    for (const PathRatePoint& p : s.path_points)
      if (p.converged && (!best || p.rate > best->rate)) best = &p;
    s.recommendations.push_back(
        best ? "path_rate: fastest within " + fmt(100 * s.options.path_rate_target) +
                   " % of the run 4x slower is " + fmt(best->rate) +
                   " 1/s (I = " + fmt(best->inertial_number) + ", cpu " + fmt(best->cpu_s) + " s)"
             : "path_rate: no swept rate is within " + fmt(100 * s.options.path_rate_target) +
                   " % of the run 4x slower");
  }
  // Recommendations: per factor, the cheapest value that meets the target.
  for (const std::string factor :
       {"dt_factor", "n_particles", "inertial_number", "relax", "dt_factor_tight"}) {
    const auto& swept = s.options.factors;
    if (std::find(swept.begin(), swept.end(), factor) == swept.end()) continue;
    const SweepPoint* best = nullptr;
    for (const SweepPoint* p : ok_points(s, factor))
      if (p->meets_target && (!best || p->cpu_s < best->cpu_s)) best = p;
    s.recommendations.push_back(best ? factor + ": cheapest meeting error <= " + fmt(target) +
                                           " is " + fmt(best->value) + " (error " +
                                           fmt(best->error) + ", cpu " + fmt(best->cpu_s) + " s)"
                                     : factor + ": no value meets error <= " + fmt(target));
  }
}

void write_sweep_h5(const SweepSummary& s, ResultsWriter& out) {
  const std::string g = "/sweep";
  out.attr("/", "scenario", s.scenario_toml);
  out.attr(g, "quick", std::int64_t{s.options.quick});
  out.attr(g, "target", s.options.target);
  out.attr(g, "directions", std::int64_t{s.options.directions});
  out.attr(g, "base_n", std::int64_t{s.options.base_n});
  out.attr(g, "threads", std::int64_t{s.options.threads});
  out.attr(g, "elastic_amplitude", s.elastic_amplitude);
  out.attr(g, "plastic_amplitude", s.plastic_amplitude);
  out.attr(g, "stability_limit_factor", s.stability_limit_factor);
  out.attr(g, "wall_s", s.wall_s);
  out.attr(g, "cpu_s", s.cpu_s);
  out.attr(g, "breaks", s.breaks);
  out.attr(g, "recommendations", s.recommendations);
  // Named numbers as attributes of one group.
  auto put = [&out](const std::string& group,
                    std::initializer_list<std::pair<const char*, double>> values) {
    for (const auto& [k, v] : values) out.attr(group, k, v);
  };
  for (const SweepState& st : s.states) {
    const std::string sg = paths::state("n" + std::to_string(st.n_particles), g);
    out.attr(sg, "n_particles", std::int64_t{st.n_particles});
    put(sg, {{"volume_fraction", st.volume_fraction},
             {"pressure_star", st.pressure_star},
             {"eps_dev", st.eps_dev},
             {"coordination", st.coordination},
             {"prepare_wall_s", st.prepare_wall_s},
             {"prepare_cpu_s", st.prepare_cpu_s},
             {"ref_major", st.ref_major},
             {"ref_minor", st.ref_minor},
             {"ref_inclination_deg", st.ref_inclination_deg}});
  }
  out.attr(g, "path_rate_target", s.options.path_rate_target);
  for (std::size_t i = 0; i < s.path_points.size(); ++i) {
    const PathRatePoint& p = s.path_points[i];
    char name[48];
    std::snprintf(name, sizeof name, "/path_rate/p%03zu", i);
    const std::string pg = g + name;
    out.attr(pg, "status", p.status);
    out.attr(pg, "note", p.note);
    put(pg, {{"rate", p.rate},
             {"wall_s", p.wall_s},
             {"cpu_s", p.cpu_s},
             {"steps", static_cast<double>(p.steps)}});
    if (p.status != "ok") continue;
    put(pg, {{"inertial_number", p.inertial_number},
             {"ratio", p.ratio},
             {"ratio_stderr", p.ratio_stderr},
             {"window_samples", static_cast<double>(p.window_samples)}});
    out.attr(pg, "ratio_per_seed", p.ratio_per_seed);
    out.attr(pg, "ratio_stderr_per_seed", p.ratio_stderr_per_seed);
    out.attr(pg, "has_slower", std::int64_t{p.has_slower});
    if (p.has_slower) {
      out.attr(pg, "change_4x", p.change_4x);
      out.attr(pg, "converged", std::int64_t{p.converged});
    }
  }
  for (std::size_t i = 0; i < s.points.size(); ++i) {
    const SweepPoint& p = s.points[i];
    char name[32];
    std::snprintf(name, sizeof name, "/points/p%03zu", i);
    const std::string pg = g + name;
    for (const auto& [k, v] : {std::pair<const char*, const std::string&>{"factor", p.factor},
                               {"method", p.method},
                               {"envelope", p.envelope},
                               {"status", p.status},
                               {"note", p.note}})
      out.attr(pg, k, v);
    out.attr(pg, "n_particles", std::int64_t{p.n_particles});
    out.attr(pg, "meets_target", std::int64_t{p.meets_target});
    out.attr(pg, "pareto", std::int64_t{p.pareto});
    put(pg, {{"value", p.value},
             {"dt_factor", p.dt_factor},
             {"inertial_number", p.inertial_number},
             {"relax_kinetic_to_elastic", p.relax},
             {"amplitude", p.amplitude},
             {"wall_s", p.wall_s},
             {"cpu_s", p.cpu_s},
             {"steps_per_probe", p.steps_per_probe},
             {"reference_relax_steps", p.reference_relax_steps},
             {"converged_fraction", p.converged_fraction}});
    if (p.status != "ok") continue;  // no numbers where there is no envelope
    put(pg, {{"error", p.error},
             {"error_rms", p.error_rms},
             {"major", p.major},
             {"minor", p.minor},
             {"inclination_deg", p.inclination_deg},
             {"err_major", p.err_major},
             {"err_minor", p.err_minor},
             {"err_inclination_deg", p.err_inclination_deg},
             {"err_center", p.err_center}});
    out.attr(pg, "center", std::vector<double>{p.center_x, p.center_y});
    out.write(pg + datasets::kThetaDeg, p.theta_deg);
    std::vector<Eigen::Vector2d> pairs;
    for (std::size_t k = 0; k < p.stress_star_x.size(); ++k)
      pairs.emplace_back(p.stress_star_x[k], p.stress_star_y[k]);
    out.write(pg + datasets::kStressStar, pairs);
  }
}

std::string sweep_csv(const SweepSummary& s) {
  std::ostringstream c;
  c << std::setprecision(6);
  c << "factor,value,method,envelope,status,n_particles,dt_factor,inertial_number,"
       "relax_kinetic_to_elastic,amplitude,wall_s,cpu_s,steps_per_probe,reference_relax_steps,"
       "converged_fraction,"
       "error,error_rms,major,minor,inclination_deg,center_x,center_y,err_major,err_minor,"
       "err_inclination_deg,err_center,meets_target,pareto,note\n";
  for (const SweepPoint& p : s.points) {
    const bool ok = p.status == "ok";
    auto num = [&](double x) {
      if (ok) c << x;
      c << ',';
    };
    c << p.factor << ',' << p.value << ',' << p.method << ',' << p.envelope << ',' << p.status
      << ',' << p.n_particles << ',' << p.dt_factor << ',' << p.inertial_number << ',' << p.relax
      << ',' << p.amplitude << ',';
    num(p.wall_s);
    num(p.cpu_s);
    num(p.steps_per_probe);
    num(p.reference_relax_steps);
    num(p.converged_fraction);
    for (double x : {p.error, p.error_rms, p.major, p.minor, p.inclination_deg, p.center_x,
                     p.center_y, p.err_major, p.err_minor, p.err_inclination_deg, p.err_center})
      num(x);
    std::string note = p.note;
    std::replace(note.begin(), note.end(), '"', '\'');
    c << p.meets_target << ',' << p.pareto << ",\"" << note << "\"\n";
  }
  return c.str();
}

std::string sweep_path_csv(const SweepSummary& s) {
  if (s.path_points.empty()) return {};
  std::ostringstream c;
  c << std::setprecision(6);
  c << "rate,status,inertial_number,ratio,ratio_stderr,window_samples,change_4x,converged,steps,"
       "wall_s,cpu_s,note\n";
  for (const PathRatePoint& p : s.path_points) {
    const bool ok = p.status == "ok";
    c << p.rate << ',' << p.status << ',';
    if (ok)
      c << p.inertial_number << ',' << p.ratio << ',' << p.ratio_stderr << ',' << p.window_samples
        << ',';
    else
      c << ",,,,";
    if (ok && p.has_slower)
      c << p.change_4x << ',' << p.converged << ',';
    else
      c << ",,";
    std::string note = p.note;
    std::replace(note.begin(), note.end(), '"', '\'');
    c << p.steps << ',' << p.wall_s << ',' << p.cpu_s << ",\"" << note << "\"\n";
  }
  return c.str();
}

}  // namespace rendulic::app

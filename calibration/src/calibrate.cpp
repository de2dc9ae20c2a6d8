// Two-level calibration with held-out check (calibrate.hpp; docs/calibration.md "Two levels").
#include "rendulic/calibration/calibrate.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <sstream>

#include "rendulic/core/comma_list.hpp"
#include "rendulic/core/conventions.hpp"
#include "rendulic/core/errors.hpp"
#include "rendulic/core/statistics.hpp"
#include "rendulic/models/law.hpp"

namespace rendulic::calibration {

bool CalibrationOptions::IsValid(std::string* why) const {
  if (model.empty()) {
    if (why) *why = "no model named";
    return false;
  }
  if (global_start_evaluations < 10) {
    if (why) *why = "global_start_evaluations must be >= 10";
    return false;
  }
  return objective.IsValid(why) && solver.IsValid(why);
}

namespace {

// The share of the driver's substep cap above which calibrate() warns that the fit may have
// ended on that cap (DriverLoad).
constexpr double kNearSubstepLimit = 0.5;

StateSummary analyse_state(const StateData& s) {
  StateSummary out;
  out.label = s.label;
  out.pressure = pressure(s.stress);
  out.f_dev = signed_deviator(s.fabric);
  out.eps_dev = s.eps_dev;
  out.volume_fraction = s.volume_fraction;
  if (const EnvelopeRecord* e = s.elastic_envelope()) {
    out.elastic = fit_rendulic_stiffness(*e);
    out.has_elastic = out.elastic.ok;
  }
  if (const EnvelopeRecord* e = s.plastic_envelope()) {
    out.plastic = plastic_features(*e);
    out.has_plastic = out.plastic.ok;
  }
  return out;
}

// Relative rms sqrt(sum r^2 / sum w) of the blocks whose state is `label` ("" = all).
double misfit(const std::vector<ResidualBlock>& blocks, const std::vector<double>& r,
              const std::string& label, const std::string& kind_prefix = "") {
  double s = 0.0, w = 0.0;
  for (const auto& b : blocks) {
    if (!label.empty() && b.state != label) continue;
    if (!kind_prefix.empty() && b.kind.rfind(kind_prefix, 0) != 0) continue;
    for (int i = 0; i < b.size; ++i) s += r[b.offset + i] * r[b.offset + i];
    w += b.weight;
  }
  return w > 0.0 ? std::sqrt(s / w) : 0.0;
}

}  // namespace

std::vector<std::string> default_holdout(const CalibrationData& data) {
  std::vector<const StateData*> order;
  for (const auto& s : data.states) order.push_back(&s);
  std::stable_sort(order.begin(), order.end(), [](const StateData* a, const StateData* b) {
    return std::abs(a->eps_dev) < std::abs(b->eps_dev);
  });
  std::vector<std::string> out;
  if (order.size() < 3) return out;
  for (std::size_t i = 1; i + 1 < order.size(); i += 2) out.push_back(order[i]->label);
  return out;
}

ModelScore yardstick_score(const CalibrationData& data, const std::string& model,
                           const std::vector<double>& params, int n_free,
                           const std::vector<std::string>& fitted,
                           const std::vector<std::string>& held_out,
                           const models::StepOptions& step) {
  const std::unique_ptr<models::Law> law = models::make_law(model);
  if (!law) throw InputError("yardstick: unknown model '" + model + "'");
  ModelScore out;
  out.model = model;
  out.n_free = n_free;
  out.fitted_states = fitted;
  out.held_out_states = held_out;
  // Any parameter serves as the (unused) free one: only the residuals at `params` are needed.
  const ParameterSpace space(*law, params, {law->parameter_info()[0].name});
  const std::vector<double> z = space.to_z(params);
  auto score_blocks = [&](const std::vector<std::string>& states, bool is_held_out) {
    if (states.empty()) return;
    const Objective y(model, data, states, space,
                      yardstick_options(step, !is_held_out && !data.path.empty()));
    std::vector<double> ry(y.num_residuals());
    const bool ok = y.residuals(z.data(), ry.data());
    for (const auto& b : y.blocks()) {
      BlockScore bs;
      bs.state = b.state;
      bs.envelope = b.envelope;
      bs.kind = yardstick_kind(b);
      bs.id = b.state == "path" ? "path/" + bs.kind : b.state + "/" + b.envelope + "/" + bs.kind;
      bs.held_out = is_held_out;
      bs.components = b.size;
      bs.scale = b.scale;
      bs.noise = b.noise;
      double s2 = 0.0;
      for (int i = 0; i < b.size; ++i) s2 += ry[b.offset + i] * ry[b.offset + i];
      bs.misfit = ok ? std::sqrt(s2 / b.weight) : std::numeric_limits<double>::infinity();
      out.blocks.push_back(bs);
    }
  };
  score_blocks(fitted, false);
  score_blocks(held_out, true);
  return out;
}

std::vector<StateSummary> per_state_analysis(const CalibrationData& data) {
  std::vector<StateSummary> out;
  for (const auto& s : data.states) out.push_back(analyse_state(s));
  return out;
}

CalibrationSummary calibrate(const CalibrationData& data, const CalibrationOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) throw InputError("calibrate: " + why);
  const std::unique_ptr<models::Law> law = models::make_law(options.model);
  if (!law) {
    throw InputError("calibrate: unknown model '" + options.model +
                     "' (known: " + comma_list(models::law_names()) + ")");
  }
  if (data.states.empty()) throw InputError("calibrate: no states in the data");
  CalibrationSummary out;
  out.model = options.model;
  out.k_star = data.k_star;
  for (const auto& pi : law->parameter_info()) {
    out.param_names.push_back(pi.name);
    out.param_units.push_back(pi.unit);
  }
  const std::vector<std::string> holdout =
      options.holdout.size() == 1 && options.holdout[0] == "auto" ? default_holdout(data)
                                                                  : options.holdout;
  const std::set<std::string> hold(holdout.begin(), holdout.end());
  for (const auto& h : hold)
    if (!data.find(h))
      throw InputError("calibrate: held-out state '" + h +
                       "' is not in the data (states: " + comma_list(data.labels()) + ")");
  for (const auto& s : data.states)
    (hold.count(s.label) ? out.held_out_states : out.fitted_states).push_back(s.label);
  if (out.fitted_states.empty()) throw InputError("calibrate: every state is held out");

  // Level 1.
  std::vector<StateSummary> level1;
  for (const auto& s : data.states) {
    level1.push_back(analyse_state(s));
    level1.back().held_out = hold.count(s.label) > 0;
  }

  // Start values: law defaults, then level-1 numbers, then the user's.
  std::vector<double> values = law->default_parameters();
  auto set = [&](const std::string& name, double v) {
    const int i = law->parameter_index(name);
    if (i < 0 || !std::isfinite(v)) return;
    const auto& pi = law->parameter_info()[i];
    values[i] = std::clamp(v, pi.lower, pi.upper);
  };
  bool has_plastic = false;
  if (options.level_one_start) {
    std::vector<double> bs, gs, ps, b_over_p;
    double num = 0.0, den = 0.0, cf_num = 0.0, cf_den = 0.0;
    for (const auto& st : level1) {
      if (st.held_out) continue;
      has_plastic = has_plastic || st.has_plastic;
      ps.push_back(st.pressure);
      if (!st.has_elastic) continue;
      bs.push_back(st.elastic.B);
      if (st.pressure > 0.0) b_over_p.push_back(st.elastic.B / st.pressure);
      gs.push_back(st.elastic.G);
      // A = beta_A F_dev B (docs/models.md section 2): least squares through the origin.
      num += st.elastic.A * st.f_dev * st.elastic.B;
      den += std::pow(st.f_dev * st.elastic.B, 2);
    }
    for (const auto& s : data.states) {
      if (hold.count(s.label)) continue;
      const EnvelopeRecord* e = s.elastic_envelope();
      const double trf = s.fabric.trace();
      if (!e || !e->has_fabric() || !(trf > 0.0)) continue;
      // Elastic fabric response c_F tr(d_eps) F / tr(F): regression of the measured pairs.
      for (std::size_t i = 0; i < e->size(); ++i) {
        const Eigen::Vector2d unit = rendulic_pair(e->strain_tensor(i).trace() * s.fabric / trf);
        cf_num += unit.dot(e->fabric[i]);
        cf_den += unit.squaredNorm();
      }
    }
    const double p_med = median(ps);
    if (p_med > 0.0) set("p_ref", p_med);
    if (!bs.empty()) {
      set(law->parameter_index("B") >= 0 ? "B" : "K", median(bs));
      set("G", median(gs));
    }
    if (den > 0.0) set("beta_A", num / den);
    // hypoplastic_wu has no stiffness parameter: its bulk modulus at p I is -(c1 + c2/3) p.
    // The published constants (a sand at kPa) can be ~100x stiffer, relative to p, than a
    // packing; started there, the first 2e-3 probe already drives tr(sigma) negative. Scale all
    // four together to the measured B/p: the same law shape, the data's stiffness.
    const int ic1 = law->parameter_index("c1"), ic2 = law->parameter_index("c2");
    if (ic1 >= 0 && ic2 >= 0 && !b_over_p.empty()) {
      const double b_wu = -(values[ic1] + values[ic2] / 3.0);
      const double scale = b_wu > 0.0 ? median(b_over_p) / b_wu : 0.0;
      if (scale > 0.0 && std::isfinite(scale))
        for (const char* c : {"c1", "c2", "c3", "c4"}) {
          const int i = law->parameter_index(c);
          if (i >= 0) set(c, scale * values[i]);
        }
    }
    if (cf_den > 0.0 && cf_num > 0.0) set("c_F", cf_num / cf_den);
  } else {
    for (const auto& st : level1) has_plastic = has_plastic || (!st.held_out && st.has_plastic);
  }
  for (const auto& [name, v] : options.values) {
    const int i = law->parameter_index(name);
    if (i < 0) throw InputError("calibrate: " + law->unknown_parameter(name));
    const auto& pi = law->parameter_info()[i];
    if (!(v >= pi.lower && v <= pi.upper))
      throw InputError("calibrate: --value " + pi.out_of_bounds(v));
    values[i] = v;
  }
  ObjectiveOptions oo = options.objective;
  const bool elastic_law =
      options.model == "isotropic_elastic" || options.model == "anisotropic_elastic";
  bool dropped = false;
  if (elastic_law && options.elastic_laws_use_elastic_data_only) {
    dropped = (oo.path && !data.path.empty()) || has_plastic;
    oo.path = false;
    oo.plastic_envelopes = false;
  }
  const bool use_path = oo.path && !data.path.empty();
  const std::vector<std::string> free =
      options.free.empty()
          ? default_free_parameters(options.model, static_cast<int>(out.fitted_states.size()),
                                    use_path, has_plastic)
          : options.free;
  ParameterSpace space(*law, values, free, options.bounds);
  out.free_mask.assign(out.param_names.size(), false);
  for (const auto& f : space.free()) out.free_mask[f.index] = true;

  // Level 2: maximum likelihood (selection.hpp) unless asked otherwise.
  const Objective objective(options.model, data, out.fitted_states, space, oo);
  out.blocks = objective.blocks();
  const int nb = static_cast<int>(out.blocks.size());
  const std::vector<double> z0 = space.to_z(space.base());
  SolverOptions so = options.solver;
  so.likelihood = options.likelihood_weights;
  out.fit = solve(objective, z0, so);
  // A law that cannot be evaluated at its start parameters for a reason it gives (a UMAT's NaN
  // or inf, its PNEWDT cuts) has nothing to fit: the calibration exited 0 with a cost of inf,
  // inf standard errors written to the results file and a place in the model selection.
  if (!std::isfinite(out.fit.cost)) {
    std::vector<double> r(objective.num_residuals());
    if (!objective.residuals(z0.data(), r.data()) && !objective.failure().empty())
      throw InputError(
          "calibration of " + options.model +
          ": the model cannot be evaluated at its start parameters: " + objective.failure());
  }

  // Global start where the local fit is poor (docs/calibration.md "Global start").
  out.global_start = "not needed";
  if (options.global_start && so.backend == Backend::kCeres) {
    std::string reason;
    std::vector<double> r(objective.num_residuals());
    if (!out.fit.converged || out.fit.termination == "budget") {
      reason = "the local fit stopped by " + out.fit.termination;
    } else if (objective.residuals(out.fit.z.data(), r.data())) {
      // Stress envelopes: one predicted worse than by no response at all is a failed fit; one
      // off by more than three times its noise means the fit is not done, and then a free
      // parameter without any effect on the data says the local search sits on a plateau.
      bool above_noise = false;
      for (int b = 0; b < nb && reason.empty(); ++b) {
        if (out.blocks[b].kind != "stress") continue;
        const double mb = misfit({out.blocks[b]}, r, out.blocks[b].state, "stress");
        above_noise = above_noise || mb > 3.0 * out.blocks[b].noise;
        if (mb > 1.0)
          reason = "the stress envelope '" + out.blocks[b].envelope + "' of state '" +
                   out.blocks[b].state + "' is predicted worse than by no response at all";
      }
      for (std::size_t k = 0; k < out.fit.names.size() && reason.empty() && above_noise; ++k)
        if (k < out.fit.uncertainty.no_effect.size() && out.fit.uncertainty.no_effect[k])
          reason = "'" + out.fit.names[k] + "' has no effect on the data at the local optimum";
    }
    if (!reason.empty()) {
      SolverOptions g = so;
      g.backend = Backend::kGlobal;
      g.global_evaluations = options.global_start_evaluations;
      g.local_evaluations = std::max(10, options.global_start_evaluations / 2);
      const FitResult gf = solve(objective, out.fit.z, g);
      std::ostringstream o;
      o << "used (" << reason << "): cost " << out.fit.cost << " locally, " << gf.cost
        << " from the global start";
      const double seconds = out.fit.seconds + gf.seconds;
      const int evaluations = out.fit.evaluations + gf.evaluations;
      if (gf.cost < out.fit.cost) {
        out.fit = gf;
        o << " (kept)";
      } else {
        o << " (the local fit kept)";
      }
      out.fit.seconds = seconds;
      out.fit.evaluations = evaluations;
      out.global_start = o.str();
    }
  }
  out.warnings = out.fit.uncertainty.warnings;
  if (dropped)
    out.warnings.push_back("note: " + options.model +
                           " is elastic: fitted to the elastic envelopes only (the main path and "
                           "the elasto-plastic envelopes are outside what it can describe)");
  if (!out.fit.converged)
    out.warnings.push_back("the optimiser did not report convergence: " + out.fit.report);
  out.evaluations = objective.tally();
  if (out.fit.params.size() == out.param_names.size() && objective.integrated()) {
    // Where a prediction at the optimum needs most of the substeps a fit allows, trial points
    // beyond may have failed on that limit alone, and the fit stopped there rather than where
    // the data put it (docs/calibration.md "When to stop").
    const DriverLoad load = objective.driver_load(out.fit.params);
    const EvaluationTally& tally = out.evaluations;
    if (load.substeps > 0 && load.substeps >= kNearSubstepLimit * load.limit) {
      out.warnings.push_back(
          "at the optimum, " + load.where + " needs " + std::to_string(load.substeps) + " of the " +
          std::to_string(load.limit) +
          " driver substeps a prediction may take (calibration.max_substeps): trial points that "
          "need more count as failed, so the fit may have stopped on that limit rather than at "
          "the data's optimum");
    } else if (tally.failed_on_limit > 0) {
      // The optimum is well inside the limit, but trial points on the way failed on it alone:
      // the optimiser took them for an infinite cost and went elsewhere, which can keep a fit
      // out of a better basin (quick.toml's hypoplastic_wu under modified Euler did, silently).
      out.warnings.push_back(
          std::to_string(tally.failed_on_limit) + " of the fit's " +
          std::to_string(tally.evaluations) +
          " evaluations failed because a prediction needed more than the " +
          std::to_string(load.limit) +
          " driver substeps it may take (calibration.max_substeps): the optimiser counted those "
          "trial points as an infinite cost, so a larger calibration.max_substeps may find a "
          "lower one");
    }
  }

  // The fit's substep budget fails stiff probes fast (what the optimiser needs); the misfits at
  // the result, on the fitted and on the held-out states, are measurements and take the
  // driver's own budget, as the yardstick does.
  const models::StepOptions measure_step = yardstick_options(oo.step, use_path).step;
  std::vector<double> r(objective.num_residuals(), 0.0);
  bool ok = objective.residuals(out.fit.z.data(), r.data());
  if (!ok) {
    ObjectiveOptions measure = oo;
    measure.step = measure_step;
    ok = Objective(options.model, data, out.fitted_states, space, measure)
             .residuals(out.fit.z.data(), r.data());
  }
  if (!ok)
    out.warnings.push_back(
        "the fitted model cannot be evaluated on its own data (a probe or the "
        "path fails in the driver at the fitted parameters)");
  if (ok && use_path) out.path_misfit = misfit(out.blocks, r, "path");

  // Held-out states: predicted with the fitted parameters, never fitted.
  std::vector<double> rh;
  std::vector<ResidualBlock> hb;
  if (!out.held_out_states.empty()) {
    ObjectiveOptions ho = oo;
    ho.path = false;
    ho.step = measure_step;
    const Objective held(options.model, data, out.held_out_states, space, ho);
    hb = held.blocks();
    rh.assign(held.num_residuals(), 0.0);
    if (!held.residuals(out.fit.z.data(), rh.data())) {
      rh.clear();
      out.warnings.push_back("the fitted model cannot be evaluated at the held-out states");
    }
  }

  // The common yardstick (selection.hpp): the same blocks and scales for every law.
  out.score = yardstick_score(data, options.model, out.fit.params, space.size(), out.fitted_states,
                              out.held_out_states, oo.step);
  const SetScore all = score_set(out.score, BlockSet::kAll);
  out.fitted_misfit = all.fitted_misfit;
  if (std::isfinite(all.held_out_misfit)) out.held_out_misfit = all.held_out_misfit;
  if (use_path) objective.predict_path(out.fit.params, &out.predicted_path);

  // Parameters on a bound of their box, and those the data do not determine.
  for (std::size_t k = 0; k < out.fit.names.size(); ++k) {
    const FreeParameter& f = space.free()[k];
    const double z = out.fit.z[k], lo = space.z_lower(static_cast<int>(k)),
                 hi = space.z_upper(static_cast<int>(k));
    if (z <= lo + 1e-9 * (hi - lo) || z >= hi - 1e-9 * (hi - lo)) {
      out.at_bound.push_back(f.name);
    } else if (!std::isfinite(out.fit.stderr_[k]) ||
               out.fit.stderr_[k] > options.solver.identifiability.relative_stderr_warning *
                                        std::abs(out.fit.values[k])) {
      out.undetermined.push_back(f.name);
    }
  }

  for (auto& st : level1) {
    const StateData& s = *data.find(st.label);
    st.misfit = st.held_out ? (rh.empty() ? -1.0 : misfit(hb, rh, st.label))
                            : (ok ? misfit(out.blocks, r, st.label) : -1.0);
    bool all_ok = true;
    for (const auto& e : s.envelopes) {
      bool pok = false;
      EnvelopeRecord pe = objective.predict_envelope(out.fit.params, s, e, &pok);
      all_ok = all_ok && pok;
      if (pok) st.predicted.push_back(std::move(pe));
    }
    st.has_model = all_ok && !st.predicted.empty();
    if (st.has_model) {
      for (const auto& pe : st.predicted) {
        if (pe.elastic() && !st.model_elastic.ok) st.model_elastic = fit_rendulic_stiffness(pe);
        if (!pe.elastic() && !st.model_plastic.ok) st.model_plastic = plastic_features(pe);
      }
    }
    if (st.has_elastic && !st.elastic.note.empty())
      out.warnings.push_back("state '" + st.label + "': " + st.elastic.note);
  }
  out.states = std::move(level1);
  return out;
}

std::string CalibrationSummary::BriefReport() const {
  std::ostringstream o;
  o << "calibration of " << model << " on " << fitted_states.size() << " state(s)";
  if (!held_out_states.empty()) o << " (+" << held_out_states.size() << " held out)";
  o << ": " << (fit.converged ? "converged" : "NOT converged") << " (stopped by " << fit.termination
    << "), back end " << fit.backend << ", Jacobian " << fit.jacobian << ", cost " << fit.cost
    << ", relative rms misfit " << fitted_misfit;
  if (held_out_misfit) o << ", held-out misfit " << *held_out_misfit;
  o << ", " << fit.seconds << " s\n";
  for (std::size_t k = 0; k < fit.names.size(); ++k)
    o << "  " << fit.names[k] << " = " << fit.values[k] << " +- " << fit.stderr_[k] << "\n";
  for (const auto& s : states) {
    o << "  state " << s.label << (s.held_out ? " (held out)" : "") << ": P = " << s.pressure
      << " Pa, F_dev = " << s.f_dev;
    if (s.has_elastic)
      o << ", B = " << s.elastic.B << " G = " << s.elastic.G << " A = " << s.elastic.A << " Pa";
    if (s.has_plastic)
      o << ", shift/a = " << s.plastic.shift_ratio << " thinning b/a = " << s.plastic.thinning;
    o << ", misfit " << s.misfit << "\n";
  }
  for (const auto& w : warnings) o << "  WARNING: " << w << "\n";
  return o.str();
}

}  // namespace rendulic::calibration

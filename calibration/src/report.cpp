// JSON and HDF5 output of a calibration (report.hpp; docs/calibration.md).
#include "rendulic/calibration/report.hpp"

#include <cmath>
#include <nlohmann/json.hpp>

#include "rendulic/core/envelope_io.hpp"
#include "rendulic/core/errors.hpp"
#include "rendulic/core/option_table.hpp"
#include "rendulic/core/result_paths.hpp"

namespace rendulic::calibration {
namespace {

using Json = nlohmann::ordered_json;

// JSON has no NaN or infinity: a non-finite number (an undetermined standard error) is null.
Json num(double v) { return std::isfinite(v) ? Json(v) : Json(nullptr); }
Json pair(const Eigen::Vector2d& v) { return Json::array({num(v(0)), num(v(1))}); }

void add_stiffness(Json& o, const RendulicStiffness& s) {
  o["B"] = num(s.B);
  o["G"] = num(s.G);
  o["A"] = num(s.A);
  o["B_stderr"] = num(s.B_stderr);
  o["G_stderr"] = num(s.G_stderr);
  o["A_stderr"] = num(s.A_stderr);
  o["elastic_center"] = pair(s.center);
  o["elastic_rms"] = num(s.rms);
  o["elastic_semi_axes"] = Json::array({num(s.a), num(s.b)});
  o["elastic_inclination_deg"] = num(s.inclination_deg);
}

Json plastic_json(const PlasticFeatures& p) {
  Json o;
  o["amplitude"] = num(p.amplitude);
  o["shift"] = pair(p.shift);
  o["shift_ratio"] = num(p.shift_ratio);
  o["semi_axes"] = Json::array({num(p.a), num(p.b)});
  o["thinning"] = num(p.thinning);
  o["inclination_deg"] = num(p.inclination_deg);
  o["rms"] = num(p.rms);
  o["fabric_shift"] = pair(p.fabric_shift);
  o["fabric_semi_axes"] = Json::array({num(p.fabric_a), num(p.fabric_b)});
  o["fabric_inclination_deg"] = num(p.fabric_inclination_deg);
  return o;
}

}  // namespace

std::string to_json(const CalibrationSummary& s) {
  const FitResult& f = s.fit;
  Json o;
  o["model"] = s.model;
  Json params = Json::object();
  for (std::size_t i = 0; i < s.param_names.size(); ++i)
    params[s.param_names[i]] = num(f.params[i]);
  o["params"] = params;
  o["free"] = f.names;
  Json se = Json::object();
  for (std::size_t k = 0; k < f.names.size(); ++k) se[f.names[k]] = num(f.stderr_[k]);
  o["stderr"] = se;
  Json matrix = Json::array();
  for (Eigen::Index a = 0; a < f.correlation.rows(); ++a) {
    Json row = Json::array();
    for (Eigen::Index b = 0; b < f.correlation.cols(); ++b) row.push_back(num(f.correlation(a, b)));
    matrix.push_back(row);
  }
  o["correlation"] = {{"names", f.names}, {"matrix", matrix}};
  o["objective"] = num(f.cost);
  o["converged"] = f.converged;
  o["backend"] = f.backend;
  o["jacobian"] = f.jacobian;
  o["termination"] = f.termination;
  o["solver_report"] = f.report;
  o["at_bound"] = f.at_bound;
  o["evaluations"] = f.evaluations;
  o["objective_evaluations"] = s.evaluations.evaluations;
  o["objective_evaluations_failed"] = s.evaluations.failed;
  o["objective_evaluations_failed_on_limit"] = s.evaluations.failed_on_limit;
  o["seconds"] = num(f.seconds);
  o["n_residuals"] = f.uncertainty.n_residuals;
  o["rank"] = f.uncertainty.rank;
  o["condition_number"] = num(f.uncertainty.condition_number);
  o["global_start"] = s.global_start;
  o["undetermined"] = s.undetermined;
  const SetScore all = score_set(s.score, BlockSet::kAll);
  const SetScore stress = score_set(s.score, BlockSet::kStress);
  o["information_criterion"] = num(all.bic);
  o["information_criterion_stress"] = num(stress.bic);
  o["held_out_score"] = num(all.held_out_score);
  o["held_out_score_stress"] = num(stress.held_out_score);
  Json fitted_kind = Json::object(), held_kind = Json::object();
  for (const auto& [k, v] : all.fitted_by_kind) fitted_kind[k] = num(v);
  for (const auto& [k, v] : all.held_out_by_kind) held_kind[k] = num(v);
  o["misfit_by_kind"] = fitted_kind;
  o["held_out_misfit_by_kind"] = held_kind;
  Json yardstick = Json::array();
  for (const BlockScore& b : s.score.blocks)
    yardstick.push_back({{"id", b.id},
                         {"held_out", b.held_out},
                         {"components", b.components},
                         {"scale", num(b.scale)},
                         {"noise", num(b.noise)},
                         {"misfit", num(b.misfit)}});
  o["yardstick"] = yardstick;
  o["fitted_misfit"] = num(s.fitted_misfit);
  o["held_out_misfit"] = s.held_out_misfit ? num(*s.held_out_misfit) : Json(nullptr);
  o["path_misfit"] = s.path_misfit >= 0 ? num(s.path_misfit) : Json(nullptr);
  o["fitted_states"] = s.fitted_states;
  o["held_out_states"] = s.held_out_states;
  o["warnings"] = s.warnings;
  Json per_state = Json::object();
  for (const StateSummary& st : s.states) {
    Json j;
    j["held_out"] = st.held_out;
    j["pressure"] = num(st.pressure);
    j["F_dev"] = num(st.f_dev);
    j["eps_dev"] = num(st.eps_dev);
    j["volume_fraction"] = num(st.volume_fraction);
    j["misfit"] = st.misfit >= 0 ? num(st.misfit) : Json(nullptr);
    if (st.has_elastic) add_stiffness(j, st.elastic);
    if (st.has_plastic) j["plastic"] = plastic_json(st.plastic);
    if (st.has_model) {
      Json m = Json::object();
      if (st.model_elastic.ok) {
        m["B"] = num(st.model_elastic.B);
        m["G"] = num(st.model_elastic.G);
        m["A"] = num(st.model_elastic.A);
      }
      if (st.model_plastic.ok) m["plastic"] = plastic_json(st.model_plastic);
      j["model"] = m;
    }
    per_state[st.label] = j;
  }
  o["per_state"] = per_state;
  // Texts come from the solver and the data (state labels): invalid UTF-8 is replaced, not
  // thrown.
  return o.dump(2, ' ', false, Json::error_handler_t::replace) + "\n";
}

void write_calibration(ResultsWriter& out, const CalibrationSummary& s) {
  const std::string g = paths::calibration(s.model);
  const FitResult& f = s.fit;
  out.attr(g, "objective", f.cost);
  out.attr(g, "converged", std::int64_t{f.converged ? 1 : 0});
  out.attr(g, "backend", f.backend);
  out.attr(g, "jacobian", f.jacobian);
  out.attr(g, "fitted_misfit", s.fitted_misfit);
  if (s.held_out_misfit) out.attr(g, "held_out_misfit", *s.held_out_misfit);
  out.attr(g, "termination", f.termination);
  out.attr(g, "global_start", s.global_start);
  out.attr(g, "seconds", f.seconds);
  out.attr(g, "objective_evaluations", std::int64_t{s.evaluations.evaluations});
  out.attr(g, "objective_evaluations_failed", std::int64_t{s.evaluations.failed});
  out.attr(g, "objective_evaluations_failed_on_limit", std::int64_t{s.evaluations.failed_on_limit});
  out.attr(g, "n_free", std::int64_t{s.score.n_free});
  out.attr(g, "at_bound", s.at_bound);
  out.attr(g, "undetermined", s.undetermined);
  // The yardstick (selection.hpp): one entry per block, and its summaries.
  {
    std::vector<std::string> ids, scale_units;
    std::vector<double> misfit, noise, scale, comps, held;
    for (const auto& b : s.score.blocks) {
      ids.push_back(b.id);
      // A stress block's scale is a stress, a fabric block's a number: one unit per entry, as
      // params carries (docs/results.md "Units").
      scale_units.push_back(is_stress_kind(b.kind) ? "Pa" : "1");
      misfit.push_back(b.misfit);
      noise.push_back(b.noise);
      scale.push_back(b.scale);
      comps.push_back(b.components);
      held.push_back(b.held_out ? 1.0 : 0.0);
    }
    out.attr(g, "yardstick_blocks", ids);
    out.attr(g, "yardstick_misfit", misfit);
    out.attr(g, "yardstick_noise", noise);
    out.attr(g, "yardstick_scale", scale);
    out.attr(g, "yardstick_scale_units", scale_units);
    out.attr(g, "yardstick_components", comps);
    out.attr(g, "yardstick_held_out", held);
    const SetScore all = score_set(s.score, BlockSet::kAll);
    const SetScore stress = score_set(s.score, BlockSet::kStress);
    out.attr(g, "information_criterion", all.bic);
    out.attr(g, "information_criterion_stress", stress.bic);
    out.attr(g, "log_likelihood", -0.5 * all.deviance);
    out.attr(g, "n_residuals_criterion", std::int64_t{all.n});
    if (std::isfinite(stress.held_out_misfit))
      out.attr(g, "held_out_misfit_stress", stress.held_out_misfit);
    if (std::isfinite(all.held_out_score)) out.attr(g, "held_out_score", all.held_out_score);
    if (std::isfinite(stress.held_out_score))
      out.attr(g, "held_out_score_stress", stress.held_out_score);
    out.attr(g, "fitted_misfit_stress", stress.fitted_misfit);
    std::vector<std::string> kinds;
    for (const auto& [k, v] : all.fitted_by_kind) {
      kinds.push_back(k);
      out.attr(g, "misfit_" + k, v);
    }
    for (const auto& [k, v] : all.held_out_by_kind) out.attr(g, "held_out_misfit_" + k, v);
    out.attr(g, "blocks_covered", kinds);
  }
  if (!s.predicted_path.eps_dev.empty()) {
    out.write(g + paths::kPath + datasets::kEpsDev, s.predicted_path.eps_dev);
    out.write(g + paths::kPath + datasets::kStress, s.predicted_path.stress);  // Pa
    out.write(g + paths::kPath + datasets::kFabric, s.predicted_path.fabric);
  }
  out.attr(g, "param_names", s.param_names);
  out.attr(g, "free", f.names);
  out.attr(g, "warnings", s.warnings);
  out.attr(g, "fitted_states", s.fitted_states);
  out.attr(g, "held_out_states", s.held_out_states);
  out.write(g + datasets::kParams, f.params);
  // stderr over every parameter: 0 for fixed ones (not estimated), +inf for undetermined.
  // Matched by name: the free parameters are not listed in the law's order.
  std::vector<double> se(s.param_names.size(), 0.0);
  for (std::size_t k = 0; k < f.names.size() && k < f.stderr_.size(); ++k)
    for (std::size_t i = 0; i < s.param_names.size(); ++i)
      if (s.param_names[i] == f.names[k]) se[i] = f.stderr_[k];
  out.write(g + datasets::kStderr, se);
  // One unit per parameter (docs/results.md "Units"): the law's table, in param_names' order.
  if (s.param_units.size() == s.param_names.size()) {
    out.attr(g + datasets::kParams, "units", s.param_units);
    out.attr(g + datasets::kStderr, "units", s.param_units);
  }
  out.write(g + datasets::kCorrelation, Eigen::MatrixXd(f.correlation));
  for (const auto& st : s.states) {
    const std::string sg = paths::state(st.label, g);
    out.attr(sg, "held_out", std::int64_t{st.held_out ? 1 : 0});
    out.attr(sg, "misfit", st.misfit);
    if (st.has_elastic) {
      out.attr(sg, "B", st.elastic.B);
      out.attr(sg, "G", st.elastic.G);
      out.attr(sg, "A", st.elastic.A);
      out.attr(sg, "B_stderr", st.elastic.B_stderr);
      out.attr(sg, "G_stderr", st.elastic.G_stderr);
      out.attr(sg, "A_stderr", st.elastic.A_stderr);
    }
    if (st.has_plastic) {
      out.attr(sg, "plastic_shift", std::vector<double>{st.plastic.shift(0), st.plastic.shift(1)});
      out.attr(sg, "plastic_shift_ratio", st.plastic.shift_ratio);
      out.attr(sg, "plastic_thinning", st.plastic.thinning);
      out.attr(sg, "plastic_inclination_deg", st.plastic.inclination_deg);
    }
    for (const auto& pe : st.predicted) {
      // The law's envelope is stored as the DEM's beside it, by the one writer: starred with the
      // file's k* (docs/results.md "Units"), or with k* = 1 Pa (stress_star in Pa) for data
      // that came without one.
      EnvelopeRecord record = pe;
      record.k_star = s.k_star > 0 ? s.k_star : 1.0;
      for (const auto& p : pe.stress) record.stress_star.push_back(p / record.k_star);
      write_envelope(out, paths::envelope(sg, pe.name), record);
    }
  }
}

StoredParameters read_parameters(const ResultsReader& in, const std::string& group) {
  StoredParameters p;
  p.names = in.attr_strings(group, "param_names");
  p.values = in.read_vector(group + datasets::kParams);
  if (in.exists(group + datasets::kStderr)) p.stderr_ = in.read_vector(group + datasets::kStderr);
  const std::string where = in.path().string() + ": " + group;
  if (const std::string* again = first_repeat(p.names))
    throw InputError(where + " @param_names: '" + *again + "' given twice");
  const auto refuse = [&](const char* dataset, std::size_t n) {
    throw InputError(where + dataset + " holds " + std::to_string(n) + " values for " +
                     std::to_string(p.names.size()) + " names in @param_names");
  };
  if (p.values.size() != p.names.size()) refuse(datasets::kParams, p.values.size());
  if (!p.stderr_.empty() && p.stderr_.size() != p.names.size())
    refuse(datasets::kStderr, p.stderr_.size());
  return p;
}

bool read_model_score(const ResultsReader& in, const std::string& model, ModelScore* score) {
  const std::string g = paths::calibration(model);
  if (!in.exists(g) || !in.has_attr(g, "yardstick_blocks") || in.has_attr(g, "error")) return false;
  ModelScore m;
  m.model = model;
  m.n_free = static_cast<int>(in.attr_int(g, "n_free"));
  m.fitted_states = in.attr_strings(g, "fitted_states");
  m.held_out_states = in.attr_strings(g, "held_out_states");
  const std::vector<std::string> ids = in.attr_strings(g, "yardstick_blocks");
  const auto misfit = in.attr_doubles(g, "yardstick_misfit");
  const auto noise = in.attr_doubles(g, "yardstick_noise");
  const auto scale = in.attr_doubles(g, "yardstick_scale");
  const auto comps = in.attr_doubles(g, "yardstick_components");
  const auto held = in.attr_doubles(g, "yardstick_held_out");
  if (misfit.size() != ids.size() || noise.size() != ids.size() || scale.size() != ids.size() ||
      comps.size() != ids.size() || held.size() != ids.size())
    return false;
  for (std::size_t i = 0; i < ids.size(); ++i) {
    BlockScore b;
    b.id = ids[i];
    const auto parts = [&] {
      std::vector<std::string> p;
      std::string item;
      std::stringstream ss(ids[i]);
      while (std::getline(ss, item, '/')) p.push_back(item);
      return p;
    }();
    if (parts.size() == 2) {
      b.state = parts[0];
      b.kind = parts[1];
    } else if (parts.size() == 3) {
      b.state = parts[0];
      b.envelope = parts[1];
      b.kind = parts[2];
    } else {
      return false;
    }
    b.misfit = misfit[i];
    b.noise = noise[i];
    b.scale = scale[i];
    b.components = static_cast<int>(comps[i]);
    b.held_out = held[i] != 0.0;
    m.blocks.push_back(b);
  }
  *score = std::move(m);
  return true;
}

void write_selection(ResultsWriter& out, const Selection& sel) {
  out.attr(paths::kCalibration, "selected_model", sel.selected);
  out.attr(paths::kCalibration, "selected_model_stress", sel.selected_stress);
  out.attr(paths::kCalibration, "selection", sel.sentence);
  out.attr(paths::kCalibration, "selection_rule", sel.rule);
  for (const auto& r : sel.rows) out.attr(paths::calibration(r.model), "selection_note", r.note);
}

}  // namespace rendulic::calibration

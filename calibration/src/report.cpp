// JSON and HDF5 output of a calibration (report.hpp; docs/calibration.md).
#include "rendulic/calibration/report.hpp"

#include <cmath>
#include <cstdio>
#include <sstream>

#include "rendulic/core/result_paths.hpp"

namespace rendulic::calibration {
namespace {

std::string num(double v) {
  if (!std::isfinite(v)) return "null";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

std::string str(const std::string& s) {
  std::string o = "\"";
  for (char c : s) {
    switch (c) {
      case '"':
        o += "\\\"";
        break;
      case '\\':
        o += "\\\\";
        break;
      case '\n':
        o += "\\n";
        break;
      case '\t':
        o += "\\t";
        break;
      default:
        if (static_cast<unsigned char>(c) < 0x20) {
          char b[8];
          std::snprintf(b, sizeof b, "\\u%04x", c);
          o += b;
        } else {
          o += c;
        }
    }
  }
  return o + "\"";
}

std::string pair(const Eigen::Vector2d& v) {
  std::string s = "[";
  s.append(num(v(0))).append(", ").append(num(v(1))).append("]");
  return s;
}

std::string stiffness_json(const RendulicStiffness& s) {
  std::ostringstream o;
  o << "\"B\": " << num(s.B) << ", \"G\": " << num(s.G) << ", \"A\": " << num(s.A)
    << ", \"B_stderr\": " << num(s.B_stderr) << ", \"G_stderr\": " << num(s.G_stderr)
    << ", \"A_stderr\": " << num(s.A_stderr) << ", \"elastic_center\": " << pair(s.center)
    << ", \"elastic_rms\": " << num(s.rms) << ", \"elastic_semi_axes\": [" << num(s.a) << ", "
    << num(s.b) << "], \"elastic_inclination_deg\": " << num(s.inclination_deg);
  return o.str();
}

std::string plastic_json(const PlasticFeatures& p) {
  std::ostringstream o;
  o << "{\"amplitude\": " << num(p.amplitude) << ", \"shift\": " << pair(p.shift)
    << ", \"shift_ratio\": " << num(p.shift_ratio) << ", \"semi_axes\": [" << num(p.a) << ", "
    << num(p.b) << "], \"thinning\": " << num(p.thinning)
    << ", \"inclination_deg\": " << num(p.inclination_deg) << ", \"rms\": " << num(p.rms)
    << ", \"fabric_shift\": " << pair(p.fabric_shift) << ", \"fabric_semi_axes\": ["
    << num(p.fabric_a) << ", " << num(p.fabric_b)
    << "], \"fabric_inclination_deg\": " << num(p.fabric_inclination_deg) << "}";
  return o.str();
}

}  // namespace

std::string to_json(const CalibrationSummary& s) {
  std::ostringstream o;
  const FitResult& f = s.fit;
  o << "{\n  \"model\": " << str(s.model) << ",\n  \"params\": {";
  for (std::size_t i = 0; i < s.param_names.size(); ++i)
    o << (i ? ", " : "") << str(s.param_names[i]) << ": " << num(f.params[i]);
  o << "},\n  \"free\": [";
  for (std::size_t k = 0; k < f.names.size(); ++k) o << (k ? ", " : "") << str(f.names[k]);
  o << "],\n  \"stderr\": {";
  for (std::size_t k = 0; k < f.names.size(); ++k)
    o << (k ? ", " : "") << str(f.names[k]) << ": " << num(f.stderr_[k]);
  o << "},\n  \"correlation\": {\"names\": [";
  for (std::size_t k = 0; k < f.names.size(); ++k) o << (k ? ", " : "") << str(f.names[k]);
  o << "], \"matrix\": [";
  for (Eigen::Index a = 0; a < f.correlation.rows(); ++a) {
    o << (a ? ", " : "") << "[";
    for (Eigen::Index b = 0; b < f.correlation.cols(); ++b)
      o << (b ? ", " : "") << num(f.correlation(a, b));
    o << "]";
  }
  o << "]},\n  \"objective\": " << num(f.cost)
    << ",\n  \"converged\": " << (f.converged ? "true" : "false")
    << ",\n  \"backend\": " << str(f.backend) << ",\n  \"jacobian\": " << str(f.jacobian)
    << ",\n  \"termination\": " << str(f.termination) << ",\n  \"solver_report\": " << str(f.report)
    << ",\n  \"at_bound\": [";
  for (std::size_t k = 0; k < f.at_bound.size(); ++k) o << (k ? ", " : "") << str(f.at_bound[k]);
  o << "],\n  \"evaluations\": " << f.evaluations << ",\n  \"seconds\": " << num(f.seconds)
    << ",\n  \"n_residuals\": " << f.uncertainty.n_residuals
    << ",\n  \"rank\": " << f.uncertainty.rank
    << ",\n  \"condition_number\": " << num(f.uncertainty.condition_number)
    << ",\n  \"global_start\": " << str(s.global_start) << ",\n  \"undetermined\": [";
  for (std::size_t k = 0; k < s.undetermined.size(); ++k)
    o << (k ? ", " : "") << str(s.undetermined[k]);
  const SetScore all = score_set(s.score, BlockSet::kAll);
  const SetScore stress = score_set(s.score, BlockSet::kStress);
  o << "],\n  \"information_criterion\": " << num(all.bic)
    << ",\n  \"information_criterion_stress\": " << num(stress.bic)
    << ",\n  \"held_out_score\": " << num(all.held_out_score)
    << ",\n  \"held_out_score_stress\": " << num(stress.held_out_score)
    << ",\n  \"misfit_by_kind\": {";
  bool first = true;
  for (const auto& [k, v] : all.fitted_by_kind) {
    o << (first ? "" : ", ") << str(k) << ": " << num(v);
    first = false;
  }
  o << "},\n  \"held_out_misfit_by_kind\": {";
  first = true;
  for (const auto& [k, v] : all.held_out_by_kind) {
    o << (first ? "" : ", ") << str(k) << ": " << num(v);
    first = false;
  }
  o << "},\n  \"yardstick\": [";
  for (std::size_t k = 0; k < s.score.blocks.size(); ++k) {
    const BlockScore& b = s.score.blocks[k];
    o << (k ? "," : "") << "\n    {\"id\": " << str(b.id)
      << ", \"held_out\": " << (b.held_out ? "true" : "false")
      << ", \"components\": " << b.components << ", \"scale\": " << num(b.scale)
      << ", \"noise\": " << num(b.noise) << ", \"misfit\": " << num(b.misfit) << "}";
  }
  o << "]"
    << ",\n  \"fitted_misfit\": " << num(s.fitted_misfit)
    << ",\n  \"held_out_misfit\": " << (s.held_out_misfit ? num(*s.held_out_misfit) : "null")
    << ",\n  \"path_misfit\": " << (s.path_misfit >= 0 ? num(s.path_misfit) : "null")
    << ",\n  \"fitted_states\": [";
  for (std::size_t k = 0; k < s.fitted_states.size(); ++k)
    o << (k ? ", " : "") << str(s.fitted_states[k]);
  o << "],\n  \"held_out_states\": [";
  for (std::size_t k = 0; k < s.held_out_states.size(); ++k)
    o << (k ? ", " : "") << str(s.held_out_states[k]);
  o << "],\n  \"warnings\": [";
  for (std::size_t k = 0; k < s.warnings.size(); ++k) o << (k ? ", " : "") << str(s.warnings[k]);
  o << "],\n  \"per_state\": {";
  for (std::size_t k = 0; k < s.states.size(); ++k) {
    const StateSummary& st = s.states[k];
    o << (k ? "," : "") << "\n    " << str(st.label)
      << ": {\"held_out\": " << (st.held_out ? "true" : "false")
      << ", \"pressure\": " << num(st.pressure) << ", \"F_dev\": " << num(st.f_dev)
      << ", \"eps_dev\": " << num(st.eps_dev)
      << ", \"volume_fraction\": " << num(st.volume_fraction)
      << ", \"misfit\": " << (st.misfit >= 0 ? num(st.misfit) : "null");
    if (st.has_elastic) o << ", " << stiffness_json(st.elastic);
    if (st.has_plastic) o << ", \"plastic\": " << plastic_json(st.plastic);
    if (st.has_model) {
      o << ", \"model\": {";
      bool first = true;
      if (st.model_elastic.ok) {
        o << "\"B\": " << num(st.model_elastic.B) << ", \"G\": " << num(st.model_elastic.G)
          << ", \"A\": " << num(st.model_elastic.A);
        first = false;
      }
      if (st.model_plastic.ok)
        o << (first ? "" : ", ") << "\"plastic\": " << plastic_json(st.model_plastic);
      o << "}";
    }
    o << "}";
  }
  o << "\n  }\n}\n";
  return o.str();
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
  out.attr(g, "n_free", std::int64_t{s.score.n_free});
  out.attr(g, "at_bound", s.at_bound);
  out.attr(g, "undetermined", s.undetermined);
  // The yardstick (selection.hpp): one entry per block, and its summaries.
  {
    std::vector<std::string> ids;
    std::vector<double> misfit, noise, scale, comps, held;
    for (const auto& b : s.score.blocks) {
      ids.push_back(b.id);
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
      const std::string eg = paths::envelope(sg, pe.name);
      out.write(eg + datasets::kThetaDeg, pe.theta_deg);
      out.write(eg + datasets::kStrain, pe.strain);
      // Starred like the DEM envelope beside it (docs/results.md "Units"), when k* is known.
      if (s.k_star > 0) {
        std::vector<Eigen::Vector2d> star;
        for (const auto& p : pe.stress) star.push_back(p / s.k_star);
        out.write(eg + datasets::kStressStar, star);
      } else {
        out.write(eg + datasets::kStress, pe.stress);  // Pa
      }
      out.write(eg + datasets::kFabric, pe.fabric);
      out.attr(eg, "amplitude", pe.amplitude);
    }
  }
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

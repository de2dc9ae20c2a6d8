// JSON and HDF5 output of a calibration (report.hpp; interfaces.md).
#include "rendulic/calibration/report.hpp"

#include <cmath>
#include <cstdio>
#include <sstream>

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
  const std::string g = "/calibration/" + s.model;
  const FitResult& f = s.fit;
  out.attr(g, "objective", f.cost);
  out.attr(g, "converged", std::int64_t{f.converged ? 1 : 0});
  out.attr(g, "backend", f.backend);
  out.attr(g, "jacobian", f.jacobian);
  out.attr(g, "fitted_misfit", s.fitted_misfit);
  if (s.held_out_misfit) out.attr(g, "held_out_misfit", *s.held_out_misfit);
  std::string names, free, warnings, fitted, held;
  for (const auto& n : s.param_names) names += (names.empty() ? "" : ",") + n;
  for (const auto& n : f.names) free += (free.empty() ? "" : ",") + n;
  for (const auto& w : s.warnings) warnings += (warnings.empty() ? "" : "\n") + w;
  for (const auto& n : s.fitted_states) fitted += (fitted.empty() ? "" : ",") + n;
  for (const auto& n : s.held_out_states) held += (held.empty() ? "" : ",") + n;
  out.attr(g, "param_names", names);
  out.attr(g, "free", free);
  out.attr(g, "warnings", warnings);
  out.attr(g, "fitted_states", fitted);
  out.attr(g, "held_out_states", held);
  out.write(g + "/params", f.params);
  // stderr over every parameter: 0 for fixed ones (not estimated), +inf for undetermined.
  // Matched by name: the free parameters are not listed in the law's order.
  std::vector<double> se(s.param_names.size(), 0.0);
  for (std::size_t k = 0; k < f.names.size() && k < f.stderr_.size(); ++k)
    for (std::size_t i = 0; i < s.param_names.size(); ++i)
      if (s.param_names[i] == f.names[k]) se[i] = f.stderr_[k];
  out.write(g + "/stderr", se);
  out.write(g + "/correlation", Eigen::MatrixXd(f.correlation));
  for (const auto& st : s.states) {
    const std::string sg = g + "/states/" + st.label;
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
      const std::string eg = sg + "/envelopes/" + pe.name;
      out.write(eg + "/theta_deg", pe.theta_deg);
      out.write(eg + "/strain", pe.strain);
      out.write(eg + "/stress", pe.stress);  // Pa
      out.write(eg + "/fabric", pe.fabric);
      out.attr(eg, "amplitude", pe.amplitude);
    }
  }
}

}  // namespace rendulic::calibration

// Envelope fits as HDF5 attributes (docs/results.md); see fit_io.hpp.
#include "rendulic/probes/fit_io.hpp"

#include <cmath>
#include <string>
#include <tuple>
#include <vector>

#include "rendulic/core/conventions.hpp"
#include "rendulic/core/envelope_io.hpp"
#include "rendulic/core/errors.hpp"
#include "rendulic/core/result_paths.hpp"

namespace rendulic {

void write_envelope_fit(ResultsWriter& out, const std::string& g, const EnvelopeFit& f) {
  // A refit replaces the whole group: an earlier fit's line_p_value, stderr or error stayed
  // beside the new shape, and the report read them.
  out.remove(g);
  out.attr(g, "shape", to_string(f.shape));
  out.attr(g, "center", std::vector<double>{f.center.x(), f.center.y()});
  out.attr(g, "semi_axes", std::vector<double>{f.a, f.b});
  if (f.inclination_deg) out.attr(g, "inclination_deg", *f.inclination_deg);
  out.attr(g, "rms", f.rms);
  out.attr(g, "n_points", static_cast<std::int64_t>(f.n_points));
  out.attr(g, "loss", to_string(f.loss));
  out.attr(g, "loss_scale", f.loss_scale);
  out.attr(g, "converged", static_cast<std::int64_t>(f.converged ? 1 : 0));
  out.attr(g, "selection", f.selection_note);
  if (f.line_p_value) out.attr(g, "line_p_value", *f.line_p_value);
  if (f.has_stderr) {
    out.attr(g, "center_stderr", std::vector<double>{f.center_stderr.x(), f.center_stderr.y()});
    out.attr(g, "semi_axes_stderr", std::vector<double>{f.a_stderr, f.b_stderr});
    if (f.inclination_stderr_deg) out.attr(g, "inclination_deg_stderr", *f.inclination_stderr_deg);
  }
}

EnvelopeFit read_envelope_fit(const ResultsReader& in, const std::string& g) {
  for (const char* key : {"shape", "center", "semi_axes", "rms"})
    if (!in.has_attr(g, key))
      throw InputError(in.path().string() + ": " + g + " has no fit attribute '" + key + "'");
  EnvelopeFit f;
  const std::string shape = in.attr_string(g, "shape");
  if (shape == "auto") throw InputError(in.path().string() + ": " + g + " has shape 'auto'");
  f.shape = fit_shape_from_string(shape);
  const auto c = in.attr_doubles(g, "center");
  const auto s = in.attr_doubles(g, "semi_axes");
  if (c.size() != 2 || s.size() != 2)
    throw InputError(in.path().string() + ": " + g + " center/semi_axes must have 2 values");
  f.center = {c[0], c[1]};
  f.a = s[0], f.b = s[1];
  if (in.has_attr(g, "inclination_deg")) f.inclination_deg = in.attr_double(g, "inclination_deg");
  f.rms = in.attr_double(g, "rms");
  if (in.has_attr(g, "n_points")) f.n_points = static_cast<int>(in.attr_int(g, "n_points"));
  if (in.has_attr(g, "loss")) f.loss = fit_loss_from_string(in.attr_string(g, "loss"));
  if (in.has_attr(g, "loss_scale")) f.loss_scale = in.attr_double(g, "loss_scale");
  if (in.has_attr(g, "converged")) f.converged = in.attr_int(g, "converged") != 0;
  if (in.has_attr(g, "selection")) f.selection_note = in.attr_string(g, "selection");
  if (in.has_attr(g, "line_p_value")) f.line_p_value = in.attr_double(g, "line_p_value");
  if (in.has_attr(g, "center_stderr") && in.has_attr(g, "semi_axes_stderr")) {
    const auto cs = in.attr_doubles(g, "center_stderr");
    const auto ss = in.attr_doubles(g, "semi_axes_stderr");
    if (cs.size() == 2 && ss.size() == 2) {
      f.has_stderr = true;
      f.center_stderr = {cs[0], cs[1]};
      f.a_stderr = ss[0], f.b_stderr = ss[1];
      f.covariance(0, 0) = cs[0] * cs[0];
      f.covariance(1, 1) = cs[1] * cs[1];
      f.covariance(2, 2) = ss[0] * ss[0];
      f.covariance(3, 3) = ss[1] * ss[1];
    }
    if (in.has_attr(g, "inclination_deg_stderr")) {
      f.inclination_stderr_deg = in.attr_double(g, "inclination_deg_stderr");
      const double r = deg_to_rad(*f.inclination_stderr_deg);
      f.covariance(4, 4) = r * r;
    }
  }
  return f;
}

FitAllSummary fit_state_envelopes(const ResultsReader& in, ResultsWriter& out,
                                  const std::string& state_group, const FitOptions& stress_options,
                                  const FitOptions& fabric_options) {
  FitAllSummary summary;
  const std::string eg = paths::envelopes(state_group);
  if (!in.exists(eg)) return summary;
  for (const auto& name : in.children(eg)) {
    const std::string g = paths::envelope(state_group, name);
    EnvelopeRecord record;
    try {
      record = read_envelope(in, g);
    } catch (const InputError& e) {  // malformed envelope: say so in the file, go on
      for (const char* fit_group : {paths::kFitStress, paths::kFitFabric}) {
        out.remove(g + fit_group);
        out.attr(g + fit_group, "shape", "none");
        out.attr(g + fit_group, "error", std::string(e.what()));
        ++summary.failed;
      }
      continue;
    }
    for (const auto& [response, fit_group, options] :
         {std::tuple<Response, const char*, const FitOptions&>{Response::kStress, paths::kFitStress,
                                                               stress_options},
          {Response::kFabric, paths::kFitFabric, fabric_options}}) {
      const Envelope env = envelope_of(record, response);
      if (env.size() == 0) continue;  // nothing measured (its `error` says why)
      try {
        std::string why;
        if (!env.IsValid(&why)) throw InputError(in.path().string() + ": " + g + ": " + why);
        write_envelope_fit(out, g + fit_group, fit_envelope(env, options));
        ++summary.fitted;
      } catch (const InputError& e) {  // degenerate envelope: say so in the file
        out.remove(g + fit_group);
        out.attr(g + fit_group, "shape", "none");
        out.attr(g + fit_group, "error", std::string(e.what()));
        ++summary.failed;
      }
    }
  }
  return summary;
}

FitAllSummary fit_envelopes(const ResultsReader& in, ResultsWriter& out,
                            const FitOptions& stress_options, const FitOptions& fabric_options) {
  FitAllSummary summary;
  // The run's states and those of its pressure branches (/pressure/nu<nu>/states), which the
  // run fits too: a refit left the branches' fits as they were.
  for (const std::string& root : state_roots(in)) {
    if (!in.is_group(paths::states(root))) continue;
    for (const auto& label : in.children(paths::states(root))) {
      const FitAllSummary s =
          fit_state_envelopes(in, out, paths::state(label, root), stress_options, fabric_options);
      summary.fitted += s.fitted;
      summary.failed += s.failed;
    }
  }
  return summary;
}

FitAllSummary fit_all_envelopes(const std::filesystem::path& file, const FitOptions& options) {
  // The update works on a copy of the file, so the reader of the original can stay open.
  ResultsWriter out = ResultsWriter::update(file);
  const FitAllSummary summary = fit_envelopes(ResultsReader(file), out, options, options);
  if (summary.fitted + summary.failed > 0) out.commit();  // else the copy is dropped
  return summary;
}

}  // namespace rendulic

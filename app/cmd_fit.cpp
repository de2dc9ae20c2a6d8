// `rendulic fit --in FILE.csv [--shape ellipse|line|auto] [--loss none|huber|cauchy] [--json]`
// (docs/fitting.md "The fit command"): fits one envelope from a CSV file. --json prints one object
// with shape, center, semi_axes, inclination_deg (null for a circle: undefined), rms and stderr
// (same keys, where defined), plus n_points, loss, loss_scale, converged, selection and
// line_p_value. `rendulic fit --results FILE.h5` fits every envelope of a results file again
// with today's fits (an older run's fits are replaced; the file is updated atomically), so that
// `rendulic report` judges the claims on them without repeating the DEM. Bad input is an
// InputError (exit 2) naming the culprit.
#include <cmath>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>

#include "cli_options.hpp"
#include "commands.hpp"
#include "rendulic/core/errors.hpp"
#include "rendulic/probes/envelope_csv.hpp"
#include "rendulic/probes/envelope_fit.hpp"
#include "rendulic/probes/fit_io.hpp"

namespace rendulic::app {
namespace {

struct FitCliOptions {
  std::string in;
  std::string results;
  std::string shape = "auto";
  std::string loss = "none";
  double loss_scale = 0.0;
  bool json = false;
  bool ignore_theta = false;
};

// The fit as JSON (docs/fitting.md "The fit command"); a non-finite number is null.
std::string to_json(const EnvelopeFit& f) {
  nlohmann::ordered_json j;
  j["shape"] = to_string(f.shape);
  j["center"] = {f.center.x(), f.center.y()};
  j["semi_axes"] = {f.a, f.b};
  j["inclination_deg"] = f.inclination_deg ? nlohmann::ordered_json(*f.inclination_deg) : nullptr;
  j["rms"] = f.rms;
  nlohmann::ordered_json se = nlohmann::ordered_json::object();
  if (f.has_stderr) {
    se["center"] = {f.center_stderr.x(), f.center_stderr.y()};
    se["semi_axes"] = {f.a_stderr, f.b_stderr};
    if (f.inclination_stderr_deg) se["inclination_deg"] = *f.inclination_stderr_deg;
  }
  j["stderr"] = se;
  j["n_points"] = f.n_points;
  j["loss"] = to_string(f.loss);
  j["loss_scale"] = f.loss_scale;
  j["converged"] = f.converged;
  j["used_theta"] = f.used_theta;
  j["selection"] = f.selection_note;
  if (f.line_p_value) j["line_p_value"] = *f.line_p_value;
  // One line: one fit, one JSON object (docs/fitting.md "The fit command").
  return j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

}  // namespace

Subcommand add_fit(CLI::App& parent) {
  auto o = std::make_shared<FitCliOptions>();
  auto* sub = parent.add_subcommand("fit", "Fit an ellipse or a line to one envelope (CSV)");
  auto* in = sub->add_option("--in", o->in,
                             "CSV file; header names the columns: x,y required (Rendulic "
                             "response coordinates), theta_deg optional (probe directions)");
  auto* results = sub->add_option("--results", o->results,
                                  "results file (HDF5): fit every envelope's stress and fabric "
                                  "pairs again and store the fits in place (atomically)");
  in->excludes(results);
  sub->add_option("--shape", o->shape,
                  "ellipse, line, or auto (line unless the ellipse fits significantly better: "
                  "docs/fitting.md); a circle is reported as such, without inclination")
      ->check(one_of(fit_shape_choices()))
      ->capture_default_str();
  sub->add_option("--loss", o->loss, "robust loss of the orthogonal distances")
      ->check(one_of(fit_loss_choices()))
      ->capture_default_str();
  sub->add_option("--loss-scale", o->loss_scale,
                  "distance at which the robust loss starts to discount a point, in data units "
                  "(0: automatic, 1.345 or 2.385 robust sigmas)")
      ->check(positive_number(true))
      ->capture_default_str();
  sub->add_flag("--ignore-theta", o->ignore_theta,
                "do not use the theta_deg column (fit the points alone)");
  sub->add_flag("--json", o->json, "print one JSON object");
  return {sub, [o]() -> int {
            if (o->in.empty() == o->results.empty())
              throw InputError("fit: give --in FILE.csv (one envelope) or --results FILE.h5");
            FitOptions opts;
            opts.shape = fit_shape_from_string(o->shape);
            opts.loss = fit_loss_from_string(o->loss);
            opts.loss_scale = o->loss_scale;
            opts.use_theta = !o->ignore_theta;
            if (!o->results.empty()) {
              const FitAllSummary s = fit_all_envelopes(o->results, opts);
              // Nothing was written; "fits: 0 fitted, 0 not fittable, stored in FILE" and exit 0
              // said otherwise.
              if (s.fitted + s.failed == 0)
                throw InputError(o->results +
                                 ": no envelope to fit (the probes and linear_response stages "
                                 "of a run, or `rendulic probe FILE.h5:LABEL`, make them)");
              if (o->json) {
                nlohmann::json j;
                j["fitted"] = s.fitted;
                j["not_fittable"] = s.failed;
                std::cout << j.dump() << "\n";
              } else {
                std::cout << "fits: " << s.fitted << " fitted, " << s.failed
                          << " not fittable, stored in " << o->results << "\n";
              }
              return 0;
            }
            Envelope env = read_envelope_csv(o->in);
            const EnvelopeFit f = fit_envelope(env, opts);
            if (o->json)
              std::cout << to_json(f) << "\n";
            else
              std::cout << f.BriefReport();
            return 0;
          }};
}

}  // namespace rendulic::app

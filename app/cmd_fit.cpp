// `rendulic fit --in FILE.csv [--shape ellipse|line|auto] [--loss none|huber|cauchy] [--json]`
// (docs/fitting.md "The fit command"): fits one envelope from a CSV file. --json prints one object
// with shape, center, semi_axes, inclination_deg (null for a circle: undefined), rms and stderr
// (same keys, where defined), plus n_points, loss, loss_scale, converged, selection and
// line_p_value. Bad input is an InputError (exit 2) naming the culprit.
#include <cmath>
#include <iostream>
#include <memory>
#include <sstream>

#include "commands.hpp"
#include "rendulic/core/errors.hpp"
#include "rendulic/probes/envelope_csv.hpp"
#include "rendulic/probes/envelope_fit.hpp"

namespace rendulic::app {
namespace {

struct FitCliOptions {
  std::string in;
  std::string shape = "auto";
  std::string loss = "none";
  double loss_scale = 0.0;
  bool json = false;
  bool ignore_theta = false;
};

std::string num(double v) {
  if (!std::isfinite(v)) return "null";  // never reached for a valid fit; JSON has no NaN
  std::ostringstream o;
  o.precision(17);
  o << v;
  return o.str();
}

std::string str(const std::string& s) {
  std::string o = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') o += '\\';
    if (static_cast<unsigned char>(c) < 0x20) {
      o += ' ';
      continue;
    }
    o += c;
  }
  return o + "\"";
}

std::string pair(double x, double y) { return "[" + num(x) + ", " + num(y) + "]"; }

std::string to_json(const EnvelopeFit& f) {
  std::ostringstream o;
  o << "{\"shape\": " << str(to_string(f.shape))
    << ", \"center\": " << pair(f.center.x(), f.center.y()) << ", \"semi_axes\": " << pair(f.a, f.b)
    << ", \"inclination_deg\": " << (f.inclination_deg ? num(*f.inclination_deg) : "null")
    << ", \"rms\": " << num(f.rms) << ", \"stderr\": {";
  if (f.has_stderr) {
    o << "\"center\": " << pair(f.center_stderr.x(), f.center_stderr.y())
      << ", \"semi_axes\": " << pair(f.a_stderr, f.b_stderr);
    if (f.inclination_stderr_deg) o << ", \"inclination_deg\": " << num(*f.inclination_stderr_deg);
  }
  o << "}, \"n_points\": " << f.n_points << ", \"loss\": " << str(to_string(f.loss))
    << ", \"loss_scale\": " << num(f.loss_scale)
    << ", \"converged\": " << (f.converged ? "true" : "false")
    << ", \"used_theta\": " << (f.used_theta ? "true" : "false")
    << ", \"selection\": " << str(f.selection_note);
  if (f.line_p_value) o << ", \"line_p_value\": " << num(*f.line_p_value);
  o << "}";
  return o.str();
}

}  // namespace

Subcommand add_fit(CLI::App& parent) {
  auto o = std::make_shared<FitCliOptions>();
  auto* sub = parent.add_subcommand("fit", "Fit an ellipse or a line to one envelope (CSV)");
  sub->add_option("--in", o->in,
                  "CSV file; header names the columns: x,y required (Rendulic response "
                  "coordinates), theta_deg optional (probe directions)")
      ->required();
  sub->add_option("--shape", o->shape,
                  "ellipse, line, or auto (line unless the ellipse fits significantly better: "
                  "docs/fitting.md); a circle is reported as such, without inclination")
      ->check(CLI::IsMember({"ellipse", "line", "auto"}))
      ->capture_default_str();
  sub->add_option("--loss", o->loss, "robust loss of the orthogonal distances")
      ->check(CLI::IsMember({"none", "huber", "cauchy"}))
      ->capture_default_str();
  sub->add_option("--loss-scale", o->loss_scale,
                  "distance at which the robust loss starts to discount a point, in data units "
                  "(0: automatic, 1.345 or 2.385 robust sigmas)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  sub->add_flag("--ignore-theta", o->ignore_theta,
                "do not use the theta_deg column (fit the points alone)");
  sub->add_flag("--json", o->json, "print one JSON object");
  return {sub, [o]() -> int {
            Envelope env = read_envelope_csv(o->in);
            FitOptions opts;
            opts.shape = fit_shape_from_string(o->shape);
            opts.loss = fit_loss_from_string(o->loss);
            opts.loss_scale = o->loss_scale;
            opts.use_theta = !o->ignore_theta;
            const EnvelopeFit f = fit_envelope(env, opts);
            if (o->json)
              std::cout << to_json(f) << "\n";
            else
              std::cout << f.BriefReport();
            return 0;
          }};
}

}  // namespace rendulic::app

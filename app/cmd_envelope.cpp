// `rendulic envelope` (docs/models.md "Model envelopes and `rendulic envelope`"): the response
// envelope a constitutive model predicts at a given state, over the DEM probe set (docs/physics.md
// section 5). Parameters and state come from small TOML files (models/material_io.hpp); `--json`
// prints theta_deg, strain, stress (Pa) and fabric as Rendulic pairs, plus the driver's error
// report.
#include <algorithm>
#include <cstdio>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "cli_options.hpp"
#include "commands.hpp"
#include "rendulic/core/comma_list.hpp"
#include "rendulic/core/decimal.hpp"
#include "rendulic/core/errors.hpp"
#include "rendulic/core/log.hpp"
#include "rendulic/models/envelope.hpp"
#include "rendulic/models/material_io.hpp"
#include "rendulic/models/umat.hpp"

namespace rendulic::app {
namespace {

nlohmann::ordered_json pairs(const std::vector<Eigen::Vector2d>& v) {
  nlohmann::ordered_json a = nlohmann::ordered_json::array();
  for (const auto& p : v) a.push_back({p(0), p(1)});
  return a;
}

}  // namespace

// An option as the front end spells it (EnvelopeRequest::cli): "--substeps 7" on the command
// line, "substeps = 7" in Python's keyword arguments.
std::string spelt(bool cli, const char* name, const std::string& value) {
  return (cli ? "--" : "") + std::string(name) + (cli ? " " : " = ") + value;
}

std::unique_ptr<models::Law> law_for(const std::string& model, const std::string& umat,
                                     const std::string& params, bool params_is_text, bool cli) {
  // A user's UMAT (docs/umat.md): its library and its PROPS file, named as the user gave them.
  const std::string with_umat = cli ? "--model umat" : "model 'umat'";
  if (model == "umat" && umat.empty())
    throw InputError(with_umat + " needs " + spelt(cli, "umat", cli ? "PATH.so" : "'PATH.so'") +
                     " (the UMAT library)");
  if (model != "umat" && !umat.empty())
    throw InputError(spelt(cli, "umat", cli ? umat : "'" + umat + "'") + " goes with " + with_umat +
                     ", not with " + (cli ? "--model " + model : "'" + model + "'"));
  if (model == "umat") {
    const std::string file = spelt(cli, "params", cli ? "FILE.toml" : "'FILE.toml'");
    if (params_is_text)
      throw InputError("a UMAT's parameters come from a TOML file (" + file +
                       "), not a dictionary: docs/umat.md");
    if (params.empty())
      throw InputError(with_umat + " needs " + file + " (props, nstatv, ...: docs/umat.md)");
    return models::make_umat_law(umat, params);
  }
  std::unique_ptr<models::Law> law = models::make_law(model);
  if (!law) {
    throw InputError((cli ? "--model" : "model") + std::string(": unknown model '") + model +
                     "' (known: " + comma_list(models::law_names()) + ", umat)");
  }
  if (params_is_text)
    models::parse_parameters_toml(params, "parameters", law.get());
  else if (!params.empty())
    models::load_parameters_toml(params, law.get());
  return law;
}

models::MaterialState state_for(const models::Law& law, const std::string& state,
                                bool state_is_text) {
  return state_is_text ? models::parse_state_toml(state, "state", law)
                       : models::load_state_toml(state, law);
}

// The CLI's options check these before; the words here are for the Python module, whose
// arguments have the same names without "--". The driver's own checks (StepOptions::IsValid)
// call them by its fields' names, fixed_substeps among them, which no user sets.
models::StepOptions step_options_for(const std::string& scheme, double tolerance, int substeps,
                                     bool cli) {
  models::StepOptions step;
  if (!models::scheme_from_name(scheme, &step.scheme))
    throw InputError("scheme: " + not_one_of(scheme, models::kSchemeNames));
  if (!(tolerance > 0.0 && tolerance < 1.0))
    throw InputError("tolerance = " + decimal_g(tolerance) + " is out of range (0, 1)");
  if (substeps < 1 || substeps > step.max_substeps)
    throw InputError("substeps = " + std::to_string(substeps) + " is out of range [1, " +
                     std::to_string(step.max_substeps) + "]");
  // An error-controlled scheme chooses its own substeps: a count given with it did nothing,
  // without a word, to a user who meant it to make the envelope finer.
  if (substeps != 1 && step.scheme != models::Scheme::kExplicitEuler)
    log::warning(spelt(cli, "substeps", std::to_string(substeps)), " has no effect: the ", scheme,
                 " scheme chooses its substeps by its error control (a fixed number: the "
                 "explicit scheme)");
  step.tolerance = tolerance;
  step.fixed_substeps = substeps;
  return step;
}

EnvelopeRecord envelope_for(const EnvelopeRequest& o, std::string* law_name) {
  const std::unique_ptr<models::Law> law =
      law_for(o.model, o.umat, o.params, o.params_is_text, o.cli);
  const models::MaterialState state = state_for(*law, o.state, o.state_is_text);
  const auto& methods = models::kEnvelopeMethodNames;
  const auto method = std::ranges::find(methods, o.method);
  if (method == methods.end()) throw InputError("method: " + not_one_of(o.method, methods));
  models::EnvelopeOptions opt;
  opt.amplitude = o.amplitude;
  opt.directions = o.directions;
  opt.method = static_cast<models::EnvelopeMethod>(method - methods.begin());
  opt.step = step_options_for(o.scheme, o.tolerance, o.substeps, o.cli);
  // The rate method integrates nothing: a scheme, tolerance or substeps given with it did
  // nothing, without a word, to a user who meant them to make the envelope more accurate.
  if (opt.method == models::EnvelopeMethod::kRate) {
    const EnvelopeRequest defaults;
    std::vector<std::string> unused;
    if (o.scheme != defaults.scheme) unused.push_back(spelt(o.cli, "scheme", o.scheme));
    if (o.tolerance != defaults.tolerance)
      unused.push_back(spelt(o.cli, "tolerance", decimal_g(o.tolerance)));
    if (o.substeps != defaults.substeps)
      unused.push_back(spelt(o.cli, "substeps", std::to_string(o.substeps)));
    if (!unused.empty())
      log::warning(comma_list(unused), unused.size() == 1 ? " has" : " have",
                   " no effect: the rate method evaluates the rate law once and integrates "
                   "nothing");
  }
  std::string why;
  if (!opt.IsValid(&why)) throw InputError("envelope options: " + why);
  try {
    EnvelopeRecord env = models::model_envelope(*law, state, opt);
    if (law_name) *law_name = std::string(law->name());
    return env;
  } catch (const InputError& e) {
    throw InputError("envelope of " + o.model + " at " + (o.state_is_text ? "the state" : o.state) +
                     ": " + e.what());
  }
}

namespace {

int run_envelope(const EnvelopeRequest& o, bool json) {
  std::string law_name;
  const EnvelopeRecord env = envelope_for(o, &law_name);
  const double max_error_estimate = env.attributes.at("max_error_estimate");
  const bool within_tolerance = env.attributes.at("within_tolerance") != 0.0;
  if (!within_tolerance)
    std::cerr << "rendulic: warning: explicit probes exceeded the tolerance " << o.tolerance
              << " (largest local error estimate " << max_error_estimate
              << "); use --scheme modified-euler\n";

  if (json) {
    nlohmann::ordered_json j;
    j["model"] = law_name;
    if (!o.umat.empty()) j["umat"] = o.umat;
    j["amplitude"] = o.amplitude;
    j["method"] = o.method;
    j["scheme"] = o.scheme;
    j["tolerance"] = o.tolerance;
    j["max_error_estimate"] = max_error_estimate;
    j["within_tolerance"] = within_tolerance;
    j["theta_deg"] = env.theta_deg;
    j["strain"] = pairs(env.strain);
    j["stress"] = pairs(env.stress);
    j["fabric"] = pairs(env.fabric);
    std::cout << j.dump(2) << "\n";
    return 0;
  }
  // The scheme and tolerance only where they made the envelope: the rate method has none.
  std::printf("# %s envelope, |d_eps| = %g, %d directions, %s", law_name.c_str(), o.amplitude,
              o.directions, o.method.c_str());
  if (o.method == "rate")
    std::printf("\n");
  else
    std::printf(" (%s, tolerance %g)\n", o.scheme.c_str(), o.tolerance);
  std::printf("# Rendulic pairs (sqrt2 lateral, axial); stress in Pa\n");
  std::printf("%10s %14s %14s %16s %16s %14s %14s\n", "theta_deg", "strain_x", "strain_y",
              "stress_x", "stress_y", "fabric_x", "fabric_y");
  for (std::size_t i = 0; i < env.size(); ++i)
    std::printf("%10.4f %14.6e %14.6e %16.8e %16.8e %14.6e %14.6e\n", env.theta_deg[i],
                env.strain[i](0), env.strain[i](1), env.stress[i](0), env.stress[i](1),
                env.fabric[i](0), env.fabric[i](1));
  return 0;
}

}  // namespace

Subcommand add_envelope(CLI::App& parent) {
  auto opts = std::make_shared<EnvelopeRequest>();
  opts->cli = true;
  auto json = std::make_shared<bool>(false);
  auto* sub = parent.add_subcommand("envelope", "Envelope predicted by a constitutive model");
  sub->add_option("--model", opts->model,
                  "Constitutive law: " + comma_list(models::law_names()) + ", umat (with --umat)")
      ->required();
  sub->add_option("--umat", opts->umat,
                  "Shared library of an Abaqus UMAT (entry umat_ or umat), with --model umat "
                  "(docs/umat.md)");
  sub->add_option("--params", opts->params,
                  "TOML file of parameters (keys = the law's parameter names; missing keys keep "
                  "their defaults; for a UMAT: props, prop_names, nstatv, statev, bounds)")
      ->check(file_name());
  sub->add_option("--state", opts->state,
                  "TOML file of the state: stress (3x3, Pa), fabric (3x3), volume_fraction")
      ->required();
  sub->add_option("--amplitude", opts->amplitude, "Probe amplitude |d_eps| (Frobenius norm)")
      ->required();
  sub->add_option("--directions", opts->directions, "Number of probe directions")
      ->check(integer_in_range(models::kEnvelopeDirectionsMin, models::kEnvelopeDirectionsMax))
      ->capture_default_str();
  sub->add_flag("--json", *json, "Print one JSON object");
  sub->add_option("--method", opts->method,
                  "integrated: each probe integrated by the driver; rate: one evaluation of the "
                  "rate law (the exact incremental envelope)")
      ->check(one_of({models::kEnvelopeMethodNames.begin(), models::kEnvelopeMethodNames.end()}))
      ->capture_default_str();
  sub->add_option("--scheme", opts->scheme,
                  "modified-euler or bogacki-shampine (error controlled; the third-order "
                  "bogacki-shampine takes 5-10x fewer rate evaluations on a law without a yield "
                  "surface), auto (bogacki-shampine without a yield surface, modified-euler with "
                  "one) or explicit (fixed substeps; reports when its error estimate exceeds the "
                  "tolerance)")
      ->check(one_of(
          std::vector<std::string>(models::kSchemeNames.begin(), models::kSchemeNames.end())))
      ->capture_default_str();
  sub->add_option("--tolerance", opts->tolerance, "Local relative error tolerance per substep")
      ->capture_default_str()
      ->check(real_in_range(0.0, 1.0, /*open=*/true));
  sub->add_option("--substeps", opts->substeps, "Substeps of the explicit scheme")
      ->check(integer_in_range(1, models::StepOptions{}.max_substeps))
      ->capture_default_str();
  return {sub, [opts, json]() -> int { return run_envelope(*opts, *json); }};
}

}  // namespace rendulic::app

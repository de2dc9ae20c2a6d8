// The `probes`, `linear_response` and `fits` stages of `rendulic run` (docs/probes.md,
// docs/fitting.md; docs/physics.md sections 5-6). Probes and linear response work on the relaxed
// states the `states` stage left in memory; fits read every envelope already written (through a
// reader on the writer's temporary file) and add fit_stress / fit_fabric beside it. An envelope
// that cannot be fitted (no fabric change at all, a degenerate set) gets shape "none" and the
// reason, never an invented fit.
#include <atomic>
#include <map>

#include "progress.hpp"
#include "rendulic/core/decimal.hpp"
#include "rendulic/core/envelope_io.hpp"
#include "rendulic/core/errors.hpp"
#include "rendulic/core/log.hpp"
#include "rendulic/core/result_paths.hpp"
#include "rendulic/dem/probe_campaign.hpp"
#include "rendulic/dem/probe_elastic_range.hpp"
#include "rendulic/probes/envelope_fit.hpp"
#include "rendulic/probes/fit_io.hpp"
#include "stages.hpp"

namespace rendulic::app {
namespace {

const std::vector<std::pair<std::string, dem::DemSystem>>& relaxed_states(
    const DemRunSession& session, const char* stage) {
  const auto& relaxed = session.relaxed;
  if (relaxed.empty())
    throw InputError(std::string("run: stage '") + stage +
                     "' needs the stage 'states' in run.stages");
  return relaxed;
}

// Counts the probes of a stage on its progress display: `total` probes over all states.
void count_probes(dem::ProbeOptions& o, Progress& progress, std::atomic<long>& done, long total) {
  o.probe_done = [&progress, &done, total] { progress.count(++done, total); };
  o.stop = stop_checker();
}

void campaign(const Scenario& sc, ResultsWriter& out, const RunContext& ctx,
              const DemRunSession& session, const std::vector<std::string>& methods,
              const char* stage) {
  dem::ProbeOptions o = dem::probe_options_from(sc);
  if (ctx.threads > 0) o.threads = ctx.threads;
  const auto& states = relaxed_states(session, stage);
  Progress progress(ctx, stage);
  std::atomic<long> done{0};
  count_probes(
      o, progress, done,
      static_cast<long>(states.size() * methods.size() * o.planes.size() * o.amplitudes.size()) *
          o.directions);
  for (const auto& [label, state] : states) {
    progress.start_task("state " + label + ", probe");
    write_probe_campaign(state, paths::state(label), methods, o, out);
  }
}

FitOptions fit_options(const Scenario& sc, const std::string& quantity) {
  FitOptions o;
  o.shape = fit_shape_from_string(sc.get_string("fits." + quantity + "_shape"));
  o.loss = fit_loss_from_string(sc.get_string("fits.loss"));
  o.use_theta = sc.get_bool("fits.use_theta");
  std::string why;
  if (!o.IsValid(&why)) throw InputError("fits: " + why);
  return o;
}

}  // namespace

void stage_probes(const Scenario& sc, ResultsWriter& out, const RunContext& ctx,
                  DemRunSession& session) {
  campaign(sc, out, ctx, session, dem::probe_methods_from(sc), "probes");
}

void stage_linear_response(const Scenario& sc, ResultsWriter& out, const RunContext& ctx,
                           DemRunSession& session) {
  dem::ProbeOptions o = dem::probe_options_from(sc);
  if (ctx.threads > 0) o.threads = ctx.threads;
  const auto& states = relaxed_states(session, "linear_response");
  Progress progress(ctx, "linear_response");
  long done = 0;
  for (const auto& [label, state] : states) {
    progress.start_task("state " + label);
    progress.count(done++, static_cast<long>(states.size()));
    try {
      const auto known = session.linear_responses.find(label);
      write_probe_campaign(state, paths::state(label), {"linear_response"}, o, out,
                           known == session.linear_responses.end() ? nullptr : &known->second);
    } catch (const std::runtime_error& e) {
      // A network with no elastic response (unstable even at its energy minimum) is a
      // finding about that state, not a failure of the run: record it, say it, go on.
      for (const std::string& plane : o.planes)
        for (double a : o.amplitudes) {
          const std::string g = paths::envelope(paths::state(label),
                                                paths::envelope_name("linear_response", a, plane));
          out.attr(g, "method", "linear_response");
          out.attr(g, "amplitude", a);
          out.attr(g, "plane", plane);
          out.attr(g, "error", std::string(e.what()));
        }
      log::warning("no linear response for state ", label, ": ", e.what());
    }
  }
}

void stage_elastic_range(const Scenario& sc, ResultsWriter& out, const RunContext& ctx,
                         DemRunSession& session) {
  dem::ProbeOptions o = dem::probe_options_from(sc);
  if (ctx.threads > 0) o.threads = ctx.threads;
  const dem::ElasticRangeOptions eo = dem::elastic_range_options_from(sc);
  const auto& states = relaxed_states(session, "elastic_range");
  Progress progress(ctx, "elastic_range");
  std::atomic<long> done{0};
  count_probes(o, progress, done,
               static_cast<long>(states.size() * eo.amplitudes.size() *
                                 dem::elastic_range_directions().size()));
  // Every state's ladder at once: their probes share one pool of tasks (dem::elastic_ranges).
  std::vector<const dem::DemSystem*> systems;
  for (const auto& [label, state] : states) systems.push_back(&state);
  progress.start_task("probe");
  std::vector<dem::ElasticRange> ranges = dem::elastic_ranges(systems, eo, o);
  std::size_t k = 0;
  for (const auto& [label, state] : states) {
    dem::ElasticRange& r = ranges[k++];
    write_elastic_range(out, paths::elastic_range(paths::state(label)), r, eo);
    // Kept for the linear_response stage; moved, not copied (it holds per-particle arrays),
    // now that the range is written.
    if (r.linear.ok) session.linear_responses[label] = std::move(r.linear);
    log::info("state ", label, ": yield strain ", r.yield_strain,
              r.yielded ? "" : " (no departure within the ladder: a lower bound)");
  }
}

std::vector<dem::Envelope> write_probe_campaign(const dem::DemSystem& state,
                                                const std::string& state_group,
                                                const std::vector<std::string>& methods,
                                                const dem::ProbeOptions& options,
                                                ResultsWriter& out,
                                                const dem::LinearResponse* known) {
  return dem::probe_campaign(
      state, methods, options,
      [&](const std::string& method, double amplitude, const dem::Envelope& env,
          const dem::LinearResponse* lr) {
        const std::string group =
            paths::envelope(state_group, paths::envelope_name(method, amplitude, env.plane.name));
        write_envelope(out, group, env);
        if (const auto a = env.attributes.find("affine_force_over_tolerance");
            a != env.attributes.end() && a->second < dem::kMinAffineForceOverTolerance)
          log::warning(group, ": the affine step leaves net forces of only ",
                       decimal_g(a->second, 2),
                       " x the force tolerance (probes.force_tolerance), so FIRE stops short of "
                       "the non-affine relaxation and the envelope keeps part of the affine, too "
                       "stiff response; raise the amplitude or lower probes.force_tolerance");
        if (lr) {
          if (lr->direction_dependent() && amplitude == options.amplitudes.front())
            log::warning(state_group, ": ", lr->n_coulomb_limit, " of ", lr->n_backbone_contacts,
                         " contacts at the Coulomb limit",
                         lr->n_rolling_limit > 0 ? " and " + std::to_string(lr->n_rolling_limit) +
                                                       " at the rolling limit"
                                                 : std::string(),
                         ": the frictional linear response depends on the loading direction "
                         "(treated as sticking: an upper bound), not an elastic envelope");
          out.write(group + datasets::kStiffness, Eigen::MatrixXd(lr->stiffness));
          out.write(group + datasets::kFabricStiffness, Eigen::MatrixXd(lr->fabric_stiffness));
        }
      },
      known);
}

void write_elastic_range(ResultsWriter& out, const std::string& g, const dem::ElasticRange& r,
                         const dem::ElasticRangeOptions& options) {
  out.create_group(g);
  out.write(g + datasets::kAmplitude, r.amplitude);
  out.write(g + datasets::kMinorOverElastic, r.minor_over_elastic);
  out.write(g + datasets::kMajorOverElastic, r.major_over_elastic);
  out.write(g + datasets::kCenterOverA, r.center_over_a);
  out.write(g + datasets::kKContinue, r.k_continue);
  out.write(g + datasets::kKReverse, r.k_reverse);
  out.write(g + datasets::kDeparture, r.departure);
  out.write(g + datasets::kThetaDeg, dem::elastic_range_directions());
  // Every probe of the ladder, amplitude by amplitude (rows a * 4 + direction).
  std::vector<Eigen::Matrix3d> ds, df, fv, fr, fc;
  std::map<std::string, std::vector<double>> diagnostics;
  for (const dem::Envelope& e : r.envelopes) {
    ds.insert(ds.end(), e.d_stress.begin(), e.d_stress.end());
    df.insert(df.end(), e.d_fabric.begin(), e.d_fabric.end());
    fv.insert(fv.end(), e.d_fabric_volume.begin(), e.d_fabric_volume.end());
    fr.insert(fr.end(), e.d_fabric_rotation.begin(), e.d_fabric_rotation.end());
    fc.insert(fc.end(), e.d_fabric_contacts.begin(), e.d_fabric_contacts.end());
    for (const auto& [name, values] : e.diagnostics) {
      auto& v = diagnostics[name];
      v.insert(v.end(), values.begin(), values.end());
    }
  }
  out.write(g + datasets::kDStress, ds);
  out.write(g + datasets::kDFabric, df);
  if (fv.size() == ds.size()) {
    out.write(g + datasets::kDFabricVolume, fv);
    out.write(g + datasets::kDFabricRotation, fr);
    out.write(g + datasets::kDFabricContacts, fc);
  }
  for (const auto& [name, values] : diagnostics)
    if (values.size() == ds.size()) out.write(g + "/" + name, values);
  out.write(g + datasets::kSeconds, r.seconds);
  out.attr(g, "yield_strain", r.yield_strain);
  out.attr(g, "yielded", std::int64_t{r.yielded});
  out.attr(g, "elastic_to", r.elastic_to);
  out.attr(g, "tolerance", options.tolerance);
  out.attr(g, "method", options.method);
  out.attr(g, "elastic_major", r.elastic_major);
  out.attr(g, "elastic_minor", r.elastic_minor);
  out.attr(g, "elastic_k", r.elastic_k);
  out.attr(g, "elastic_reference", r.elastic_reference);
  if (!r.elastic_reference_note.empty())
    out.attr(g, "elastic_reference_note", r.elastic_reference_note);
}

void register_fit_keys(ScenarioSchema& s) {
  s.add({.path = "fits.stress_shape",
         .type = KeyType::kString,
         .default_value = std::string("auto"),
         .unit = "-",
         .help = "Shape fitted to stress envelopes; auto chooses ellipse or line by the "
                 "statistical test of docs/fitting.md (steady-state envelopes collapse to lines).",
         .choices = fit_shape_choices()});
  s.add({.path = "fits.fabric_shape",
         .type = KeyType::kString,
         .default_value = std::string("auto"),
         .unit = "-",
         .help = "Shape fitted to fabric envelopes; auto chooses ellipse or line by the same "
                 "test as the stress (the seed draws lines; line forces that).",
         .choices = fit_shape_choices()});
  s.add({.path = "fits.loss",
         .type = KeyType::kString,
         .default_value = std::string("none"),
         .unit = "-",
         .help = "Robust loss of the fits (none, huber, cauchy; scales in docs/fitting.md).",
         .choices = fit_loss_choices()});
  s.add({.path = "fits.use_theta",
         .type = KeyType::kBool,
         .default_value = true,
         .unit = "-",
         .help = "Use the probe directions (affine start, exact for a linear law plus shift)."});
}

void fit_state_envelopes(const Scenario& sc, ResultsWriter& out, const std::string& state_group) {
  // read_back(): the `error` of an envelope that cannot be fitted is stored, and named the
  // temporary file, gone once the run ended.
  rendulic::fit_state_envelopes(out.read_back(), out, state_group, fit_options(sc, "stress"),
                                fit_options(sc, "fabric"));
}

void stage_fits(const Scenario& sc, ResultsWriter& out, const RunContext& ctx) {
  const FitAllSummary s =
      fit_envelopes(out.read_back(), out, fit_options(sc, "stress"), fit_options(sc, "fabric"));
  (void)ctx;
  log::info("fits: ", s.fitted, " fitted, ", s.failed, " not fittable");
}

}  // namespace rendulic::app

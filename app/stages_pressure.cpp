// The `pressure` stage of `rendulic run` (docs/physics.md section 5, "beyond the seed": the elastic
// range and its dependence on pressure; docs/dem.md "Pressure branches"). The isotropic stage
// snapshots the loading at pressure.volume_fractions on its way to nu_max; from each snapshot
// this stage repeats, under /pressure/nu<nu>, what the run does at nu_max: relaxation, the
// undrained path (at the main path's inertial number: its rate scaled by sqrt(P / P_main), or
// path.inertial_number held), the states brought to rest, and for each state the stages the
// run requests among elastic_range, probes and linear_response; the `fits` stage, which comes
// after this one, fits the branches' envelopes with the main ones. The branches' states are
// stored without their configuration (positions, checkpoint): the main states carry those.
#include <cmath>

#include "rendulic/core/errors.hpp"
#include "rendulic/core/log.hpp"
#include "rendulic/core/result_paths.hpp"
#include "rendulic/dem/probe_campaign.hpp"
#include "rendulic/dem/probe_elastic_range.hpp"
#include "rendulic/dem/run_protocol.hpp"
#include "stages.hpp"

namespace rendulic::app {

void stage_pressure(const Scenario& sc, ResultsWriter& out, const RunContext& ctx,
                    DemRunSession& session) {
  if (!session.options) throw InputError("run: stage 'pressure' needs the stages before it");
  const dem::DemRunOptions& o = *session.options;
  if (o.branch_nu.empty())
    throw InputError("run: stage 'pressure' needs pressure.volume_fractions");
  if (session.branches.size() != o.branch_nu.size())
    throw InputError("run: stage 'pressure' needs the stage 'isotropic' in run.stages");
  dem::ProbeOptions po = dem::probe_options_from(sc);
  if (ctx.threads > 0) po.threads = ctx.threads;
  const bool with_range = stage_requested(sc, "elastic_range");
  const bool with_probes = stage_requested(sc, "probes");
  const bool with_lr = stage_requested(sc, "linear_response");
  for (auto& [nu, snapshot] : session.branches) {
    const std::string G = paths::pressure_branch(nu);
    log::info("[pressure] branch nu = ", nu);
    dem::DemSystem sys = snapshot;
    const dem::RelaxSummary r = dem::relax(sys, o.relax);
    dem::use_run_material(sys, o);  // as the main branch, from its path on
    const dem::Measures start = sys.measure();
    dem::PathOptions path = o.path;
    // The same inertial number as the main path: I ~ rate / sqrt(P) (a path that holds
    // path.inertial_number does so itself).
    if (path.inertial_number == 0 && session.path_start_pressure > 0 && start.pressure > 0)
      path.rate = o.path.rate * std::sqrt(start.pressure / session.path_start_pressure);
    out.attr(G, "volume_fraction", start.volume_fraction);
    out.attr(G, "pressure_star", start.pressure_star);
    out.attr(G, "coordination", start.coordination);
    out.attr(G, "relax_converged", std::int64_t{r.converged});
    const std::string path_group = G + paths::kPath;
    out.attr(path_group, "rate", path.rate);
    out.attr(path_group, "type", path.type);
    dem::PathSummary p =
        dem::run_path(sys, path, path_recorder(out, path_group, o.system.material));
    out.attr(path_group, "max_inertial_number", p.max_inertial_number);
    auto rested = rest_states(p.snapshots, o.state_rest, o.state_labels, ctx);
    for (std::size_t k = 0; k < rested.size(); ++k) {
      const std::string& label = o.state_labels[k];
      const std::string sg = paths::state(label, G);
      const dem::DemSystem& state = rested[k].first;
      write_state(out, sg, state, rested[k].second, o.state_rest.minimise.force_tolerance, false);
      dem::LinearResponse linear;  // the elastic range's reference, for the linear response
      if (with_range) {
        const dem::ElasticRangeOptions eo = dem::elastic_range_options_from(sc);
        dem::ElasticRange er = dem::elastic_range(state, eo, po);
        write_elastic_range(out, paths::elastic_range(sg), er, eo);
        log::info("[pressure] nu ", nu, " state ", label, ": yield strain ", er.yield_strain);
        linear = std::move(er.linear);
      }
      if (with_probes) write_probe_campaign(state, sg, dem::probe_methods_from(sc), po, out);
      if (with_lr) {
        try {
          write_probe_campaign(state, sg, {"linear_response"}, po, out, &linear);
        } catch (const std::runtime_error& e) {
          log::warning("no linear response for nu ", nu, " state ", label, ": ", e.what());
        }
      }
    }
  }
}

}  // namespace rendulic::app

// The elastic range of a state: a ladder of probe amplitudes in four directions, compared with
// the linear response (see probe_elastic_range.hpp; docs/probes.md "Elastic range").
#include "rendulic/dem/probe_elastic_range.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>

#include "rendulic/core/conventions.hpp"
#include "rendulic/core/envelope_record.hpp"
#include "rendulic/core/errors.hpp"
#include "rendulic/core/option_table.hpp"
#include "rendulic/core/result_paths.hpp"
#include "rendulic/dem/probe_campaign.hpp"

namespace rendulic::dem {

bool ElasticRangeOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& m) {
    if (why) *why = m;
    return false;
  };
  if (!elastic_range_option_table().check(*this, why)) return false;
  for (std::size_t i = 1; i < amplitudes.size(); ++i)
    if (!(amplitudes[i] > amplitudes[i - 1]))
      return fail("elastic_range.amplitudes: the ladder must increase");
  return true;
}

std::vector<double> elastic_range_directions() {
  return {kIsoCompressionDeg, kDevCompressionDeg, kIsoExtensionDeg, kDevExtensionDeg};
}

namespace {

// Directional stiffness (d_sigma : d_eps) / |d_eps|^2 of probe p of an envelope, Pa.
double directional_stiffness(const Envelope& env, std::size_t p) {
  const Eigen::Vector2d u = env.strain[p] / env.strain[p].norm();
  return rendulic_pair(env.d_stress[p]).dot(u) / env.amplitude;
}

std::size_t index_of(const std::vector<double>& theta, double deg) {
  for (std::size_t p = 0; p < theta.size(); ++p)
    if (std::abs(theta[p] - deg) < 1e-9) return p;
  throw std::logic_error("elastic range: direction missing");
}

}  // namespace

void locate_yield(ElasticRange& r, double tolerance) {
  const std::size_t n = r.amplitude.size();
  r.departure.assign(n, 0.0);
  for (std::size_t i = 0; i < n; ++i)
    r.departure[i] = std::max(std::abs(r.minor_over_elastic[i] - 1.0),
                              std::abs(1.0 - r.k_continue[i] / r.k_reverse[i]));
  r.yielded = false;
  r.yield_strain = n ? r.amplitude.back() : 0.0;
  r.elastic_to = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    // A non-finite departure (a reverse stiffness of zero) counts as departed.
    if (!(r.departure[i] < tolerance)) {
      r.yielded = true;
      r.yield_strain = r.amplitude[i];
      return;
    }
    r.elastic_to = r.amplitude[i];
  }
}

std::vector<ElasticRange> elastic_ranges(const std::vector<const DemSystem*>& states,
                                         const ElasticRangeOptions& options,
                                         const ProbeOptions& probe) {
  std::string why;
  if (!options.IsValid(&why)) throw InputError(why);
  const std::vector<double> theta = elastic_range_directions();
  const std::size_t i_continue = index_of(theta, kDevExtensionDeg);
  const std::size_t i_reverse = index_of(theta, kDevCompressionDeg);
  const std::size_t S = states.size(), A = options.amplitudes.size();
  std::vector<ElasticRange> ranges(S);
  // The elastic reference: the linear response's map per unit strain (Pa). A network with no
  // linear response (unstable even at its minimum: the linear_response stage records why)
  // is referred to its ladder's first rung instead, and the attribute says so.
  const auto set_reference = [](ElasticRange& r, const Eigen::Matrix2d& m) {
    const RendulicMap el = ellipse_of(m, 1.0);
    r.elastic_major = el.semi_major;
    r.elastic_minor = el.semi_minor;
    const double t = deg_to_rad(kDevExtensionDeg);
    const Eigen::Vector2d u(std::cos(t), std::sin(t));
    r.elastic_k = u.dot(m * u);
  };
  // The references one after the other on this thread, not as tasks of the team: in a pool
  // thread the factorisation of a large state (N = 9261) rounds differently, by 1e-15 of the
  // stiffness (the libraries' kernels follow where its buffers land), and then which thread
  // took which state would change the run's results.
  for (std::size_t s = 0; s < S; ++s) {
    if (probe.stop && probe.stop()) throw Cancelled("elastic range: stopped on request");
    LinearResponse& linear = ranges[s].linear;
    try {
      linear = state_linear_response(*states[s], probe);
    } catch (const std::runtime_error& e) {
      linear = LinearResponse{};
      linear.message = e.what();
    }
    if (linear.ok) {
      set_reference(ranges[s], rendulic_map_of(linear.stiffness));
    } else {
      ranges[s].elastic_reference = "first_rung";
      ranges[s].elastic_reference_note = linear.message;
    }
  }
  // Every rung of every state: minimisation probes in one pool of tasks (a rung's four probes
  // alone left a thread idle at the end of each rung: 12-14 % of the ladder's time on two
  // threads, docs/probes.md "Elastic range"); dynamic probes rung by rung.
  std::vector<std::vector<double>> seconds;
  std::vector<std::vector<Envelope>> envelopes =
      options.method == "dynamic"
          ? dynamic_envelopes(states, options.amplitudes, theta, probe, rendulic_plane(), &seconds)
          : minimisation_envelopes(states, options.amplitudes, theta, probe, rendulic_plane(),
                                   &seconds);
  for (std::size_t s = 0; s < S; ++s) {
    ElasticRange& r = ranges[s];
    for (std::size_t k = 0; k < A; ++k) {
      Envelope& env = envelopes[s][k];
      if (env.size() == 0) continue;  // an MPI worker: rank 0 assembles
      const double a = options.amplitudes[k];
      std::vector<Eigen::Vector2d> stress(env.size());
      for (std::size_t p = 0; p < env.size(); ++p) stress[p] = rendulic_pair(env.d_stress[p]);
      const RendulicMap m = fit_rendulic_map(env.strain, stress);
      if (r.amplitude.empty() && r.elastic_reference != "linear_response") {
        set_reference(r, m.map);  // the map is per unit strain (pair to pair)
      }
      r.amplitude.push_back(a);
      r.minor_over_elastic.push_back(m.semi_minor / a / r.elastic_minor);
      r.major_over_elastic.push_back(m.semi_major / a / r.elastic_major);
      r.center_over_a.push_back(m.center.norm() / m.semi_major);
      r.k_continue.push_back(directional_stiffness(env, i_continue));
      r.k_reverse.push_back(directional_stiffness(env, i_reverse));
      r.envelopes.push_back(std::move(env));
      r.seconds.push_back(seconds[s][k]);
    }
    if (!r.amplitude.empty()) locate_yield(r, options.tolerance);
  }
  return ranges;
}

ElasticRange elastic_range(const DemSystem& state, const ElasticRangeOptions& options,
                           const ProbeOptions& probe) {
  return elastic_ranges({&state}, options, probe).front();
}

const OptionTable<ElasticRangeOptions>& elastic_range_option_table() {
  using Row = OptionRow<ElasticRangeOptions>;
  static const OptionTable<ElasticRangeOptions> table({
      Row{{.path = "elastic_range.amplitudes",
           .unit = "-",
           .help = "Ladder of probe amplitudes |d_eps| of the elastic_range stage, increasing; "
                   "each is probed at 35.26, 125.26, 215.26 and 305.26 deg.",
           .min = 0.0,
           .max = 0.05,
           .min_open = true,
           .min_size = 2},
          [](ElasticRangeOptions& o) -> std::vector<double>& { return o.amplitudes; }},
      Row{{.path = "elastic_range.method",
           .unit = "-",
           .help = "Probe method of the ladder (dynamic: as the probes stage; minimisation: "
                   "quasi-static).",
           .choices = {"dynamic", "minimisation"}},
          [](ElasticRangeOptions& o) -> std::string& { return o.method; }},
      Row{{.path = "elastic_range.tolerance",
           .unit = "-",
           .help = "The response has left the elastic one where |minor axis / elastic - 1| or "
                   "|1 - k_continue / k_reverse| reaches this; the yield strain is that "
                   "amplitude (docs/probes.md).",
           .min = 0.0,
           .max = 1.0,
           .min_open = true,
           .max_open = true},
          [](ElasticRangeOptions& o) -> double& { return o.tolerance; }},
  });
  return table;
}

void register_elastic_range_keys(ScenarioSchema& schema) {
  elastic_range_option_table().register_keys(schema);
}

ElasticRangeOptions elastic_range_options_from(const Scenario& scenario) {
  ElasticRangeOptions o;
  elastic_range_option_table().read(scenario, o);
  std::string why;
  if (!o.IsValid(&why))
    throw InputError(why + " (" + scenario.origin("elastic_range.amplitudes") + ")");
  return o;
}

}  // namespace rendulic::dem

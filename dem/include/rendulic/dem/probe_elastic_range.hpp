// The elastic range of a state at rest (docs/physics.md section 5: the amplitude of
// elasto-plastic probes must lie beyond the measured elastic range of the state; docs/probes.md
// "Elastic range"). A ladder of probe amplitudes in the four directions 35.26 (isotropic
// compression), 125.26 (constant-volume axial compression: reverses the extension path),
// 215.26 (isotropic extension) and 305.26 (constant-volume axial extension: continues the path,
// i.e. reloads the state that the relaxation has unloaded), each amplitude by the probe method
// of the campaign. Per amplitude A, from the stress responses r(theta) (Rendulic pairs, Pa):
//  - the least-squares Rendulic map r = M A u + c (probe_envelope.hpp): its minor semi-axis
//    per unit strain over the linear response's, minor_over_elastic; |c| over its major
//    semi-axis, center_over_a;
//  - the directional stiffness k(theta) = r . u / A = (d_sigma : d_eps) / |d_eps|^2, at 305.26
//    (k_continue) and 125.26 (k_reverse). A linear law has k(theta + 180) = k(theta): the ratio
//    is 1 for every elastic response.
// departure(A) = max(|minor_over_elastic - 1|, |1 - k_continue / k_reverse|). The yield strain
// is the smallest amplitude of the ladder whose departure reaches `tolerance` (the response has
// left the elastic one there); elastic_to is the rung below it (the largest amplitude still
// elastic, 0 if the first rung departs): the yield lies between the two. Beyond the yield,
// single probes of a small packing are single realisations of rearrangement avalanches and
// scatter widely, so no interpolation is attempted. A state that never departs within the
// ladder has yielded = false and yield_strain = elastic_to = the largest amplitude (a lower
// bound).
#pragma once

#include <string>
#include <vector>

#include "rendulic/core/option_table.hpp"
#include "rendulic/core/scenario.hpp"
#include "rendulic/dem/dem_system.hpp"
#include "rendulic/dem/linear_response.hpp"
#include "rendulic/dem/probe_envelope.hpp"

namespace rendulic::dem {

struct ProbeOptions;

// Defaults (docs/probes.md "Elastic range", measured on quick.toml's five states): minimisation
// probes find the same yield rung as dynamic probes in 4 of 5 states (the fifth is within 0.01 of
// the tolerance in both) at a sixth of their cost; 0.1 is 2.5x the largest departure of the
// elastic rungs (0.04).
struct ElasticRangeOptions {
  std::vector<double> amplitudes = {5e-5, 2e-4, 5e-4, 1e-3, 2e-3, 5e-3, 1e-2, 2e-2};
  std::string method = "minimisation";  // or "dynamic"
  double tolerance = 0.1;
  bool IsValid(std::string* why) const;
};

// The four directions of the ladder (deg), in the order above.
std::vector<double> elastic_range_directions();

struct ElasticRange {
  std::vector<double> amplitude, minor_over_elastic, major_over_elastic, center_over_a;
  std::vector<double> k_continue, k_reverse, departure;  // k in Pa (stress per unit strain)
  double yield_strain = 0.0;
  double elastic_to = 0.0;
  bool yielded = false;
  // The linear response's (elastic) values: semi-axes of its Rendulic map per unit strain
  // (Pa) and its directional stiffness at 305.26 (= at 125.26).
  double elastic_major = 0.0, elastic_minor = 0.0, elastic_k = 0.0;
  // "linear_response", or "first_rung" when the state has none (the note says why).
  std::string elastic_reference = "linear_response", elastic_reference_note;
  // The state's linear response (state_linear_response, probe_campaign.hpp): the reference
  // where it is ok, kept so that a run need not compute it again (app/stages_probes.cpp).
  LinearResponse linear;
  std::vector<Envelope> envelopes;  // one per amplitude, the 4 directions each
  // Time of each amplitude's probes: with minimisation probes (the default) the sum of their
  // own wall times (they share a pool with the other rungs, see elastic_ranges); with dynamic
  // probes the wall time of the rung.
  std::vector<double> seconds;
};

// Departure of each rung and the yield strain by the rule above (pure: tested on its own).
void locate_yield(ElasticRange& range, double tolerance);

// The ladder of one state, by options.method with the probe options of the campaign (rate,
// time step, relaxation, force tolerance; amplitudes and directions are the ladder's). The
// elastic reference is the linear response of the state (which must be at rest), or the
// ladder's first rung if the state has none.
ElasticRange elastic_range(const DemSystem& state, const ElasticRangeOptions& options,
                           const ProbeOptions& probe);
// The ladders of several states, the same as elastic_range state by state, with the
// minimisation probes of every rung of every state in one pool of tasks.
std::vector<ElasticRange> elastic_ranges(const std::vector<const DemSystem*>& states,
                                         const ElasticRangeOptions& options,
                                         const ProbeOptions& probe);

// The keys of ElasticRangeOptions (section [elastic_range]), defaults ElasticRangeOptions{}'s.
const OptionTable<ElasticRangeOptions>& elastic_range_option_table();
void register_elastic_range_keys(ScenarioSchema& schema);
ElasticRangeOptions elastic_range_options_from(const Scenario& scenario);

}  // namespace rendulic::dem

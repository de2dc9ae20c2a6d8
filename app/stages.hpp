// The stage functions of `rendulic run` (pipeline.cpp's table) and the live DEM state they
// share within one run: the DEM stages leave the relaxed states in memory for the probe
// stages, in the DemRunSession that run_pipeline owns and hands to each stage; stages that need
// data already written (fits, calibration) read the writer's temporary file through a
// ResultsReader.
#pragma once

#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "pipeline.hpp"
#include "rendulic/dem/dem_system.hpp"
#include "rendulic/dem/probe_campaign.hpp"
#include "rendulic/dem/probe_elastic_range.hpp"
#include "rendulic/dem/protocols.hpp"
#include "rendulic/dem/scenario_keys.hpp"

namespace rendulic::app {

// Live DEM state shared by the stages of one run (one per run_pipeline call).
struct DemRunSession {
  std::optional<dem::DemSystem> system;                         // after prepare / isotropic / path
  std::vector<dem::DemSystem> snapshots;                        // on the path, states.labels order
  std::vector<std::pair<std::string, dem::DemSystem>> relaxed;  // after states
  // The relaxed states' linear responses by label, kept by elastic_range (its references) for
  // the linear_response stage: the same scenario's probe options, so the same responses.
  std::map<std::string, dem::LinearResponse> linear_responses;
  std::optional<dem::DemRunOptions> options;
  // The loading's snapshots at pressure.volume_fractions (after isotropic): (nu, system).
  std::vector<std::pair<double, dem::DemSystem>> branches;
  double path_start_pressure = 0;  // Pa, the relaxed state at nu_max the path starts from
};

// Pieces of the DEM stages that the pressure branches repeat (stages_dem.cpp).
// Appends every path sample as a row of the datasets <group>/time, strain, ... (the /path
// layout of docs/results.md).
dem::SampleFn path_recorder(ResultsWriter& out, const std::string& group,
                            const dem::Material& material);
// The snapshots brought to rest (rest.hpp) over one OpenMP team; throws naming the state if
// one is not at rest afterwards.
std::vector<std::pair<dem::DemSystem, dem::RestSummary>> rest_states(
    const std::vector<dem::DemSystem>& snapshots, const dem::RestOptions& options,
    const std::vector<std::string>& labels, const RunContext& ctx);
// A state at rest under `group`: its attributes (docs/results.md /states/<label>), stress and
// fabric; with_configuration adds positions, radii, cell lengths and the checkpoint.
void write_state(ResultsWriter& out, const std::string& group, const dem::DemSystem& sys,
                 const dem::RestSummary& rest, double force_tolerance, bool with_configuration);

// /material (docs/results.md): the contact law, density, size distribution and time step.
void write_material(ResultsWriter& out, const dem::SystemOptions& system, std::int64_t n_particles);
// The attributes of /material that hold a scenario key's value, and the key (k_star, dt and
// n_particles are derived or belong to the run); friction's and rolling's are there only when
// they are on. Read back where a file's stored scenario is not at hand.
struct MaterialAttribute {
  const char* attribute;
  const char* key;
};
inline constexpr MaterialAttribute kMaterialAttributes[] = {
    {"k", "material.k"},
    {"gamma", "material.gamma"},
    {"gamma_b", "material.gamma_b"},
    {"density", "material.density"},
    {"r_mean", "material.r_mean"},
    {"w", "material.w"},
    {"dt_factor", "dem.dt_factor"},
    {"friction", "dem.friction"},
    {"k_t_ratio", "dem.k_t_ratio"},
    {"gamma_t_ratio", "dem.gamma_t_ratio"},
    {"rolling_friction", "dem.rolling_friction"},
    {"k_r_ratio", "dem.k_r_ratio"},
    {"gamma_r_ratio", "dem.gamma_r_ratio"}};

// DEM (stages_dem.cpp).
void stage_prepare(const Scenario&, ResultsWriter&, const RunContext&, DemRunSession&);
void stage_isotropic(const Scenario&, ResultsWriter&, const RunContext&, DemRunSession&);
void stage_path(const Scenario&, ResultsWriter&, const RunContext&, DemRunSession&);
void stage_states(const Scenario&, ResultsWriter&, const RunContext&, DemRunSession&);
// Probe campaigns and linear response (stages_probes.cpp).
void stage_probes(const Scenario&, ResultsWriter&, const RunContext&, DemRunSession&);
void stage_linear_response(const Scenario&, ResultsWriter&, const RunContext&, DemRunSession&);
// The elastic range of every state (probe_elastic_range.hpp): /states/<label>/elastic_range.
void stage_elastic_range(const Scenario&, ResultsWriter&, const RunContext&, DemRunSession&);
// The pressure branches (stages_pressure.cpp): path, states at rest, elastic range, probes,
// linear response and fits from each of the loading's snapshots, under /pressure/nu<nu>.
void stage_pressure(const Scenario&, ResultsWriter&, const RunContext&, DemRunSession&);
// The probe campaign of one state written under <state_group>/envelopes/<paths::envelope_name>
// (docs/results.md), e.g. /states/<label> or a pressure branch's /pressure/nu0.7/states/<label>;
// the linear-response envelopes also store the 6x6 Mandel stiffness [Pa] and fabric stiffness as
// datasets `stiffness` and `fabric_stiffness`. Each envelope is written as soon as it is made.
// `known`: the state's linear response if the elastic range already computed it (probe_campaign).
std::vector<dem::Envelope> write_probe_campaign(const dem::DemSystem& state,
                                                const std::string& state_group,
                                                const std::vector<std::string>& methods,
                                                const dem::ProbeOptions& options,
                                                ResultsWriter& out,
                                                const dem::LinearResponse* known = nullptr);
// /states/<label>/elastic_range (docs/results.md): datasets amplitude, minor_over_elastic,
// major_over_elastic, center_over_a, k_continue, k_reverse, departure, seconds, theta_deg[4],
// d_stress[n*4,3,3], d_fabric[n*4,3,3], the fabric split and the per-probe diagnostics of the
// method (e.g. load_steps, relax_steps, iterations) of every probe; attributes
// yield_strain, elastic_to, yielded, tolerance, method, elastic_major, elastic_minor,
// elastic_k.
void write_elastic_range(ResultsWriter& out, const std::string& group,
                         const dem::ElasticRange& range, const dem::ElasticRangeOptions& options);

// Envelope fits (stages_probes.cpp): fit_stress / fit_fabric of every envelope.
void register_fit_keys(ScenarioSchema& schema);
void stage_fits(const Scenario&, ResultsWriter&, const RunContext&);
// The fits of every envelope under <state_group>/envelopes, with the fits.* options.
void fit_state_envelopes(const Scenario& sc, ResultsWriter& out, const std::string& state_group);

}  // namespace rendulic::app

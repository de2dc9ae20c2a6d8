// Probe campaigns (docs/physics.md section 5): from one relaxed state, M strain
// probes per amplitude, by one of three separate methods (never substituted for each other):
//  - dynamic: a copy of the DEM state takes the probe strain (core probe_strain, log strain,
//    diagonal) at a controlled rate, then relaxes at fixed cell until E_kin / E_el falls below
//    the threshold (or the time cap, reported per probe); d_sigma, d_F = after - before with the
//    engine's own measures (eq. 1 with the dashpot part of the contact force, eq. 2 over all
//    contacts);
//  - minimisation: the state is first brought to its nearest energy minimum at fixed cell (so
//    that residual forces of the relaxed state are not counted as response), then every probe
//    is an affine step x -> exp(-d_eps) x followed by FIRE to the force tolerance;
//  - linear_response: the exact small-strain response of the contact network
//    (linear_response.hpp), no dynamics.
// Probes are independent: they run in parallel over an OpenMP team, each on its own copy with
// the engine's inner loops forced serial, so every probe's result is a function of the state
// and its direction alone and the envelope is bitwise identical whatever the thread count.
// Under `mpirun -np K` the probes of the dynamic and minimisation envelopes are also shared
// among the ranks (probe_mpi.hpp), with the same envelope bit for bit.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "rendulic/core/scenario.hpp"
#include "rendulic/dem/dem_system.hpp"
#include "rendulic/dem/linear_response.hpp"
#include "rendulic/dem/probe_envelope.hpp"
#include "rendulic/dem/probe_minimise.hpp"
#include "rendulic/dem/probe_options.hpp"
#include "rendulic/dem/protocols.hpp"

namespace rendulic::dem {

// A worker's part of one envelope under MPI (MpiSession::serve takes it): the same envelope
// function as on rank 0, inside a ProbeTaskScope that gives the worker's share. `state` is
// what rank 0 sent: the relaxed reference for `dynamic` (rank 0 relaxed it once for all), the
// given state for `minimisation` (its reference minimisation is repeated on every rank: it is
// deterministic and costs about one probe, against sending a second kind of state).
void compute_worker_share(const std::string& method, const std::string& plane,
                          const DemSystem& state, double amplitude,
                          const std::vector<double>& theta_deg, const ProbeOptions& options);

// The probe directions: M equally spaced angles from the plane's start, 35.26 deg in the
// Rendulic plane (core plane_directions_deg).
std::vector<double> probe_directions(int m, const ProbePlane& plane = rendulic_plane());
// The loading rate for a state (1/s).
double probe_rate(const DemSystem& state, const ProbeOptions& options);

// The envelope functions probe in `plane` (core/conventions.hpp, docs/probes.md "Probe
// planes"); the Rendulic plane by default.
Envelope dynamic_envelope(const DemSystem& state, double amplitude,
                          const std::vector<double>& theta_deg, const ProbeOptions& options,
                          const ProbePlane& plane = rendulic_plane());
Envelope minimisation_envelope(const DemSystem& state, double amplitude,
                               const std::vector<double>& theta_deg, const ProbeOptions& options,
                               const ProbePlane& plane = rendulic_plane());
// A minimisation envelope's attribute `affine_force_over_tolerance`: over its probes, the
// smallest largest net force that the affine step leaves, in units of force_tolerance x the
// mean contact force. FIRE resolves the non-affine relaxation to about its inverse; below
// kMinAffineForceOverTolerance the envelope keeps part of the affine (too stiff) response, and
// the probes stage says so (quick.toml's state a, 12 directions: 1e-8 matches the linear
// response to 1e-4, 1e-10 is 55 % off, 1e-12 takes no FIRE step at all).
inline constexpr double kMinAffineForceOverTolerance = 100.0;
// envelopes[s][a]: the minimisation envelope of *states[s] at amplitudes[a], the same bits as
// minimisation_envelope, with the probes of all of them in one pool of tasks (the largest
// amplitudes first) instead of envelope by envelope: no thread idles at the end of each
// envelope's few probes (the elastic range's ladder, four directions per rung). With MPI
// ranks, envelope by envelope, as they share each envelope's probes. seconds[s][a], if
// given: the summed wall time of that envelope's probes.
std::vector<std::vector<Envelope>> minimisation_envelopes(
    const std::vector<const DemSystem*>& states, const std::vector<double>& amplitudes,
    const std::vector<double>& theta_deg, const ProbeOptions& options,
    const ProbePlane& plane = rendulic_plane(),
    std::vector<std::vector<double>>* seconds = nullptr);
// The same for dynamic probes, envelope by envelope: each envelope's probes are a pool of
// their own (dynamic_envelope); seconds[s][a]: each envelope's wall time.
std::vector<std::vector<Envelope>> dynamic_envelopes(
    const std::vector<const DemSystem*>& states, const std::vector<double>& amplitudes,
    const std::vector<double>& theta_deg, const ProbeOptions& options,
    const ProbePlane& plane = rendulic_plane(),
    std::vector<std::vector<double>>* seconds = nullptr);
// The packing of a frictionless state for the energy-based static tools (minimisation, force
// balance at rest); InputError naming dem.friction for a frictional one.
PackingData packing_of(const DemSystem& state);
// Positions, radii and cell alone, with or without friction: for the geometry of contacts
// (the fabric split of a dynamic probe), never for a contact law.
PackingData geometry_of(const DemSystem& state);
// The linear response of a state at rest: a frictional state's with its tangential springs
// (sticking contacts, docs/probes.md); a frictionless state's at its energy minimum, found
// first (minimised_first) where the state as given makes the Hessian indefinite. ok == false
// with the reason for a network that has none; throws when that minimisation fails.
LinearResponse state_linear_response(const DemSystem& state, const ProbeOptions& options);
// The linear response of the state and its envelope (throws where it has none).
Envelope linear_response_envelope(const DemSystem& state, double amplitude,
                                  const std::vector<double>& theta_deg, const ProbeOptions& options,
                                  LinearResponse* response = nullptr,
                                  const ProbePlane& plane = rendulic_plane());

// What a campaign hands on for each envelope as soon as it is made: its method and amplitude,
// the envelope, and for the linear response the response itself (its 6x6 Mandel stiffness and
// fabric stiffness), otherwise nullptr.
using EnvelopeSink = std::function<void(const std::string& method, double amplitude,
                                        const Envelope& envelope, const LinearResponse* response)>;
// The whole campaign of one state: every method x plane x amplitude, in that order, each handed to
// `sink` (the run's stages write it, app/stages_probes.cpp) and returned in the same order.
// `known`, if given and ok: the state's state_linear_response with these options, already
// computed (the run's elastic range keeps its references), used instead of a new one.
std::vector<Envelope> probe_campaign(const DemSystem& state,
                                     const std::vector<std::string>& methods,
                                     const ProbeOptions& options, const EnvelopeSink& sink = {},
                                     const LinearResponse* known = nullptr);

// Scenario keys of the probe campaigns (the table, probes.methods and the elastic range's) and
// the options they give. Throws InputError naming the key, also for a probes.dt_factor beyond
// the stability limit of the scenario's material.
void register_probe_keys(ScenarioSchema& schema);
ProbeOptions probe_options_from(const Scenario& scenario);
// The methods of the probes stage: a subset of {"dynamic", "minimisation"} (the
// linear_response stage calls probe_campaign with {"linear_response"}).
std::vector<std::string> probe_methods_from(const Scenario& scenario);

}  // namespace rendulic::dem

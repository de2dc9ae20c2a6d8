// The settings of a probe campaign (docs/physics.md section 5, docs/probes.md): ProbeOptions
// with its defaults and the table of its scenario keys (core/option_table.hpp). Apart from the
// campaigns (probe_campaign.hpp), so that the MPI layer (probe_mpi.cpp), which sends them to
// the workers, needs the settings and not the campaigns.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "rendulic/core/option_table.hpp"
#include "rendulic/dem/linear_response.hpp"
#include "rendulic/dem/probe_minimise.hpp"
#include "rendulic/dem/protocols.hpp"

namespace rendulic::dem {

struct ProbeOptions {
  int directions = 36;                            // equally spaced from 35.26 deg
  std::vector<double> amplitudes = {5e-5, 2e-3};  // |d_eps|, Frobenius
  // Probe planes by name (core/conventions.hpp kProbePlaneNames; docs/probes.md "Probe
  // planes"): every method and amplitude is probed in each.
  std::vector<std::string> planes = {"rendulic"};
  // Loading rate of the largest strain component: from the inertial number
  // I = rate 2<r> sqrt(rho / P) at the state's pressure, unless `rate` > 0 fixes it (1/s).
  double inertial_number = 1e-4;
  double rate = 0.0;
  // Time step of the dynamic probes as a fraction of t_c (dem.dt_factor's meaning); 0 keeps
  // the state's own. A probe's answer is the relaxed end state, not the collision dynamics:
  // docs/accuracy.md measured the same envelope error at 0.02 and 0.1 (relaxed to 1e-9).
  double dt_factor = 0.0;
  // Relaxation after loading (dynamic): E_kin / E_el below kinetic_to_elastic, or time_cap.
  RelaxOptions relax{1e-9, 2e-3, 200};
  // How a dynamic probe relaxes once loaded (docs/probes.md "Methods", docs/accuracy.md
  // "FIRE for the relaxation tail"): "fire" (the engine at fixed cell down to
  // relax_fire_from, then FIRE at fixed cell to `minimise`'s force tolerance; frictionless
  // packings only, a frictional one relaxes as "dynamic") or "dynamic" (the seed's: the
  // engine at fixed cell to `relax`).
  std::string relax_method = "fire";
  // "fire": the engine's relaxation first runs down to this E_kin / E_el (the inertial part of
  // a plastic probe's rearrangements), FIRE then takes the slow tail. At nine of ten measured
  // states 1e-4 moves the plastic envelopes of 1e-5 less than another realisation of the
  // method does (at the tenth by 0.3 %, where realisations agree to 0.02 %), with 56-58 % fewer
  // relaxation steps (docs/accuracy.md "FIRE from 1e-4").
  double relax_fire_from = 1e-4;
  // Minimisation probes: FIRE to max net force < force_tolerance * mean contact force.
  MinimiseOptions minimise{};
  LinearResponseOptions linear{};
  int threads = 0;  // OpenMP threads over probes; 0: OpenMP's default
  // Called after each probe this process computes, from the thread that computed it (so it
  // must be thread-safe): the run's progress display counts probes with it.
  std::function<void()> probe_done;
  // Asked before each probe this process computes (any thread): once it says true, the
  // remaining probes are skipped and the envelope throws rendulic::Cancelled (the Python
  // module's Ctrl-C, app/progress.hpp). Empty: never.
  std::function<bool()> stop;
  bool IsValid(std::string* why) const;
};

// The keys of ProbeOptions (section [probes]): their unit, range and help, the defaults being
// ProbeOptions{}'s. IsValid checks the same ranges.
const OptionTable<ProbeOptions>& probe_option_table();

}  // namespace rendulic::dem

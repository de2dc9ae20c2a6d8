// States at rest (docs/physics.md section 5: a probe starts from a state in mechanical equilibrium,
// not only one with little kinetic energy; docs/dem.md "States at rest"). Two things live here:
//  - the one equilibrium criterion of the project, force_balance(): the largest net contact
//    force on a non-rattler over the mean force of the contacts between non-rattlers. The
//    states stage, the tests and the report all use it (a dynamically relaxed state at
//    E_kin/E_el = 1e-5 sits at about 2e-2 of it; a state at rest is below kEquilibrium);
//  - bring_to_rest(): a snapshot relaxed dynamically (the seed's relaxation, relax()) and then
//    brought to its nearest energy minimum at the fixed cell by FIRE (probe_minimise.hpp), so
//    that its stress, fabric, contacts, linear response and every envelope refer to one
//    configuration at rest. A frictional packing has no energy to minimise (its tangential
//    springs depend on the history), so it is relaxed dynamically alone, on until the force
//    balance of its contact forces, tangential ones included, holds (or the time cap).
#pragma once

#include <cstdint>
#include <string>

#include "rendulic/dem/dem_system.hpp"
#include "rendulic/dem/probe_geometry.hpp"
#include "rendulic/dem/probe_minimise.hpp"
#include "rendulic/dem/protocols.hpp"

namespace rendulic::dem {

// A state counts as at rest when force_balance(...).ratio is below this.
inline constexpr double kEquilibrium = 1e-4;

struct ForceBalance {
  double max_net_force = 0.0;       // N, largest |sum of contact forces| on a non-rattler
  double mean_contact_force = 0.0;  // N, mean k delta over contacts between non-rattlers
  double ratio = 0.0;               // max_net_force / mean_contact_force; 0 without contacts
  int non_rattlers = 0;             // particles with >= 4 contacts among non-rattlers
  int contacts = 0;                 // contacts between non-rattlers
  int all_contacts = 0;             // contacts of any particles, rattlers' included
  // Frictional packings: the largest |net torque| on a non-rattler (N m) and it over the mean
  // contact force times <r>; zero without friction.
  double max_net_torque = 0.0;
  double torque_ratio = 0.0;
};
// Contacts are pairs with overlap > 0 under the linear law f = k delta (the static force of a
// state at rest); rattlers are removed iteratively (fewer than 4 contacts, measures.hpp). The
// net force on a non-rattler sums all its contacts, those with rattlers included.
ForceBalance force_balance(const PackingData& packing, double k);
// The same criterion on the engine's own contact forces (normal, with the dashpot of the
// current velocities, and tangential) and torques: the balance of a frictional packing, whose
// rattlers have fewer than rattler_min_contacts(true) contacts (measures.hpp).
ForceBalance force_balance(const DemSystem& sys);

struct RestOptions {
  RelaxOptions relax;  // the dynamic relaxation first
  // Then FIRE to max net force < force_tolerance x mean contact force (every particle).
  MinimiseOptions minimise;
  bool IsValid(std::string* why) const;
};
struct RestSummary {
  RelaxSummary relaxed;
  ForceBalance after_relax;  // the criterion after the dynamic relaxation
  MinimiseSummary minimised;
  ForceBalance at_rest;           // ... and at the minimum
  double max_displacement = 0.0;  // m, largest move of a particle by the minimisation
  Eigen::Matrix3d stress_change;  // Pa, stress at rest - after the dynamic relaxation
};

// Minimises the energy of a frictionless `sys` at its fixed cell by FIRE (options.k is taken
// from the material) and puts the state at the minimum: positions there (wrapped into the
// cell), velocities zero, forces and the neighbour list recomputed from there; clock, strain
// and step count are kept. The state is moved even if FIRE did not converge (the summary says
// so; the caller judges). Throws InputError for a frictional packing (packing_of). Also the
// dynamic probes' relaxation with probes.relax_method = "fire" (docs/probes.md).
MinimiseSummary settle_at_minimum(DemSystem& sys, const MinimiseOptions& options,
                                  double* max_displacement = nullptr);

// A frictionless packing at rest may be a saddle of its energy: its forces balance, yet its
// Hessian has negative modes, and no relaxation from rest leaves it (copies of a smaller
// periodic packing side by side often are; docs/probes.md "Replicated packings"). This moves it
// off: a step along the most negative mode (by the mean overlap), FIRE to the minimum below,
// and again while negative modes remain, at most max_rounds times. The state is put where it
// ended (as settle_at_minimum does) if it moved. A state that is not a saddle is left as it is.
struct SaddleEscape {
  int negative_modes = 0;  // of the state as given (-1: not counted)
  int remaining = 0;       // at the end
  int rounds = 0;          // steps off and minimisations
  std::int64_t iterations = 0;
  bool left = false;              // it was a saddle and is now at a minimum
  double max_displacement = 0.0;  // m, largest move of a particle
  std::string message;            // the linear response's last reason, or FIRE's
};
SaddleEscape leave_saddle(DemSystem& sys, const MinimiseOptions& options, int max_rounds = 20);

// Relaxes `sys` dynamically, then minimises its energy at the fixed cell and puts the state
// at the minimum: positions there (wrapped into the cell), velocities zero, forces and the
// neighbour list recomputed from there; clock, strain and step count are kept. Throws
// std::runtime_error if FIRE does not converge. With friction (no energy to minimise): the
// dynamic relaxation, continued until force_balance(sys) is below kEquilibrium or the
// relaxation's time cap is spent, then velocities zero; `minimised` stays empty and
// `at_rest` is the balance of the forces and torques there (the caller judges it).
RestSummary bring_to_rest(DemSystem& sys, const RestOptions& options);

}  // namespace rendulic::dem

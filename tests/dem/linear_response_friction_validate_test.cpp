// The linear response of a frictional packing without rolling resistance against the engine's
// dynamic probes (linear_response.hpp, docs/probes.md "Linear response of a frictional
// packing"): on 250 particles at rest, with three contacts at the Coulomb limit (treated as
// sticking), the stress increment of the dynamic probes (affine loading, relaxation) in four
// directions equals the linear response's (its two-contact struts kept, their spin held), at
// the state's step and at t_c / 10, and the frictionless response of the same geometry is
// nowhere near it. A validation (ctest -L validate): the packing comes to rest at the seed's
// damping in 1.78 million steps, 55 s of one core. The default suite runs the same comparison
// with rolling resistance (linear_response_friction_system_test.cpp).
#include <gtest/gtest.h>

#include "frictional_probes.hpp"

namespace rendulic::dem {
namespace {

// One packing for both checks, which are independent given the state: its relaxation to rest
// at the seed's damping (1.78 million steps, 55 s of the 57 s each check took alone when they
// were two tests, one core, 2026-12-06) is most of the cost.
TEST(LinearResponseFriction, MatchesTheEnginesDynamicProbesAtTheStatesStepAndATenthOfIt) {
  const DemSystem state = testing::frictional_packing();
  {
    SCOPED_TRACE("at the state's step");
    testing::check_at_the_states_step(state);
  }
  SCOPED_TRACE("at t_c / 10");
  testing::check_at_a_tenth_of_the_contact_time(state);
}

}  // namespace
}  // namespace rendulic::dem

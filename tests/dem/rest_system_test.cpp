// The linear response of a state brought to rest as the states stage does it (dynamic
// relaxation, then FIRE; rest.hpp) equals a finite relaxed probe at that configuration:
// central differences of minimisation probes of 1e-6 in the four directions of the elastic
// range agree with C d_eps to 1e-6 of the largest response, and so does the fabric rate of the
// backbone (the contacts between non-rattlers, which the linear response describes).
#include <gtest/gtest.h>

#include <cmath>

#include "rendulic/core/conventions.hpp"
#include "rendulic/dem/probe_campaign.hpp"
#include "rendulic/dem/probe_elastic_range.hpp"
#include "rendulic/dem/rest.hpp"

namespace rendulic::dem {
namespace {

TEST(RestLinearResponse, EqualsAFiniteRelaxedProbeAtTheMinimum) {
  GeneratedPackingOptions g;
  g.n = 250;
  g.volume_fraction = 0.78;
  g.seed = 11;
  g.minimise.force_tolerance = 1e-4;  // not at rest: the states stage brings it there
  const PackingData packing = generate_packing(g, nullptr);
  std::vector<double> radii(packing.radii.data(), packing.radii.data() + packing.size());
  DemSystem sys =
      system_from_positions(packing.positions, radii, packing.cell.lengths(), SystemOptions{});
  RestOptions ro;
  ro.relax.time_cap = 2e-6;
  const RestSummary rest = bring_to_rest(sys, ro);
  ASSERT_LT(rest.at_rest.ratio, kEquilibrium);

  ProbeOptions po;
  po.minimise.force_tolerance = 1e-12;  // the finite probes resolved far below their response
  const std::vector<double> theta = elastic_range_directions();  // two +- pairs
  const double amp = 1e-6;
  LinearResponse lr;
  const Envelope linear = linear_response_envelope(sys, amp, theta, po, &lr);
  ASSERT_TRUE(lr.ok) << lr.message;
  EXPECT_EQ(linear.attributes.at("minimised_first"), 0.0);  // already at its minimum
  const Envelope probe = minimisation_envelope(sys, amp, theta, po);
  const PackingData start = packing_of(sys);
  std::vector<std::pair<int, int>> backbone;
  for (const PairGeometry& c : find_pairs(start, 0.0))
    if (c.overlap > 0 && lr.backbone[c.i] && lr.backbone[c.j]) backbone.emplace_back(c.i, c.j);
  double stress_scale = 0, fabric_scale = 0, stress_err = 0, fabric_err = 0;
  for (std::size_t p = 0; p < 2; ++p) {  // theta[p + 2] = theta[p] + 180
    const Eigen::Matrix3d ds = 0.5 * (probe.d_stress[p] - probe.d_stress[p + 2]);
    // The fabric over the backbone contacts of the state, the ones the linear response keeps
    // (a rattler's contacts, carrying a force or not, are not part of it), after the same
    // affine step and minimisation done here.
    auto backbone_fabric = [&](std::size_t q) {
      PackingData after = start;
      const Eigen::Matrix3d A =
          (-probe_strain(theta[q], amp).diagonal()).array().exp().matrix().asDiagonal();
      after.positions = start.positions * A.transpose();
      after.cell.h = A * start.cell.h;
      MinimiseOptions mo = po.minimise;
      EXPECT_TRUE(minimise_energy(after, mo).converged);
      return Eigen::Matrix3d(fabric_of_pairs(after, backbone) - fabric_of_pairs(start, backbone));
    };
    const Eigen::Matrix3d df = 0.5 * (backbone_fabric(p) - backbone_fabric(p + 2));
    stress_err = std::max(stress_err, (ds - linear.d_stress[p]).norm());
    fabric_err = std::max(fabric_err, (df - linear.d_fabric[p]).norm());
    stress_scale = std::max(stress_scale, linear.d_stress[p].norm());
    fabric_scale = std::max(fabric_scale, linear.d_fabric[p].norm());
    EXPECT_EQ(probe.diagnostics.at("backbone_contacts_opened")[p], 0.0);
    EXPECT_EQ(probe.diagnostics.at("backbone_contacts_closed")[p], 0.0);
  }
  std::cout << "central difference vs linear response: stress " << stress_err / stress_scale
            << ", fabric " << fabric_err / fabric_scale << "\n";
  EXPECT_LT(stress_err, 1e-6 * stress_scale);
  EXPECT_LT(fabric_err, 1e-6 * fabric_scale);
}

}  // namespace
}  // namespace rendulic::dem

// The driver's load at a parameter vector (Objective::driver_load, docs/calibration.md "When to
// stop"): which integrated prediction takes the most substeps, checked against the public
// driver (models::integrate) probe by probe; calibrate()'s warning when the optimum needs most
// of the fit's substep cap, where trial points beyond fail on the cap alone; and held-out states
// predicted with the driver's own budget, not that cap; the objective's tally of evaluations
// that failed on the cap, and calibrate()'s warning when trial points did though the optimum
// is well inside it.
#include <ceres/ceres.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <memory>

#include "input_error.hpp"
#include "rendulic/calibration/calibrate.hpp"
#include "rendulic/calibration/objective.hpp"
#include "rendulic/models/driver.hpp"
#include "synthetic.hpp"

namespace rendulic::calibration {
namespace {

using testing::law_with;

CalibrationData plastic_data(const models::Law& law) {
  testing::SyntheticSpec spec;
  spec.directions = 8;
  spec.plastic_amplitude = 2e-3;
  return testing::synthetic_data(law, spec);
}

std::vector<std::string> labels_of(const CalibrationData& d) {
  std::vector<std::string> labels;
  for (const auto& s : d.states) labels.push_back(s.label);
  return labels;
}

// M_ss fitted from the truth (the other parameters held there), least squares, no global
// start: the optimum is the truth, and so are the substeps its probes need.
CalibrationOptions m_ss_from_the_truth() {
  CalibrationOptions o;
  o.model = "elastoplastic_fabric";
  o.free = {"M_ss"};
  for (const auto& [name, v] : testing::kElastoplasticTruth) o.values[name] = v;
  o.level_one_start = false;
  o.likelihood_weights = false;
  o.global_start = false;
  return o;
}

bool mentions_substeps(const std::vector<std::string>& warnings) {
  return std::any_of(warnings.begin(), warnings.end(), [](const std::string& w) {
    return w.find("driver substeps a prediction may take") != std::string::npos;
  });
}

TEST(ParameterSpaceNames, AFreeParameterListedTwiceOrUnknownIsRefusedNamingIt) {
  const auto law = law_with("elastoplastic_fabric", testing::kElastoplasticTruth);
  EXPECT_EQ(rendulic::testing::input_error([&] {
              ParameterSpace(*law, law->parameters(), {"M_ss", "G", "M_ss"});
            }),
            "parameter 'M_ss' listed twice");
  // The names it knows follow: "(known: K, G, ..., M_ss, ...)".
  const std::string unknown = rendulic::testing::input_error([&] {
    ParameterSpace(*law, law->parameters(), {"M_ss", "nope"});
  });
  EXPECT_EQ(unknown.rfind("unknown parameter 'nope' of elastoplastic_fabric (known: ", 0), 0u)
      << unknown;
  EXPECT_NE(unknown.find(", M_ss, "), std::string::npos) << unknown;
  EXPECT_EQ(unknown.back(), ')') << unknown;
  // Unknown and listed twice: the unknown name is the fault to mend (it said "listed twice").
  EXPECT_EQ(rendulic::testing::input_error([&] {
              ParameterSpace(*law, law->parameters(), {"Q", "Q"});
            }).rfind("unknown parameter 'Q' of elastoplastic_fabric (known: ", 0),
            0u);
  EXPECT_EQ(rendulic::testing::input_error([&] {
              ParameterSpace(*law, law->parameters(), {"M_ss"}, {{"nope", {0.0, 1.0}}});
            }),
            "search bounds given for 'nope', not free");
  // The law's range in the words of every number rendulic writes: std::to_string wrote
  // "[0.001000, 3.000000]", and "0.000000" for a bound below 1e-6.
  EXPECT_EQ(rendulic::testing::input_error([&] {
              ParameterSpace(*law, law->parameters(), {"M_ss"}, {{"M_ss", {0.0, 1.0}}});
            }),
            "search bounds of 'M_ss' must lie within [0.001, 3] with lower < upper");
}

TEST(DriverLoad, IsTheMostSubstepsOfAnyIntegratedProbe) {
  const auto law = law_with("elastoplastic_fabric", testing::kElastoplasticTruth);
  const CalibrationData d = plastic_data(*law);
  const std::vector<std::string> labels = labels_of(d);
  ObjectiveOptions oo;
  const Objective obj("elastoplastic_fabric", d, labels,
                      ParameterSpace(*law, law->parameters(), {"M_ss"}), oo);
  ASSERT_TRUE(obj.integrated());
  const DriverLoad load = obj.driver_load(law->parameters());
  ASSERT_TRUE(load.ok);
  EXPECT_EQ(load.limit, oo.step.max_substeps);

  // The same probes through the public driver, one by one.
  int most = 0;
  std::string where;
  for (const auto& s : d.states) {
    const models::MaterialState st = law->make_state(s.stress, s.fabric, s.volume_fraction);
    for (const auto& env : s.envelopes) {
      // Every envelope of a law with a yield surface is integrated, the elastic ones too.
      for (std::size_t i = 0; i < env.size(); ++i) {
        const models::StepResult r = models::integrate(*law, st, env.strain_tensor(i), oo.step);
        ASSERT_TRUE(r.success) << r.reason;
        if (r.attempted() > most) {
          most = r.attempted();
          where = " of state " + s.label + "'s envelope " + env.name;
        }
      }
    }
  }
  EXPECT_GT(most, 1);
  EXPECT_EQ(load.substeps, most);
  ASSERT_GE(load.where.size(), where.size());
  EXPECT_EQ(load.where.substr(load.where.size() - where.size()), where) << load.where;
}

TEST(DriverLoad, CalibrateWarnsWhereTheOptimumNeedsMostOfTheCap) {
  const auto law = law_with("elastoplastic_fabric", testing::kElastoplasticTruth);
  const CalibrationData d = plastic_data(*law);
  CalibrationOptions o = m_ss_from_the_truth();
  const CalibrationSummary quiet = calibrate(d, o);
  ASSERT_TRUE(quiet.fit.converged) << quiet.fit.report;
  std::vector<std::string> labels = quiet.fitted_states;
  const DriverLoad load =
      Objective(o.model, d, labels, ParameterSpace(*law, law->parameters(), {"M_ss"}), o.objective)
          .driver_load(quiet.fit.params);
  // The default cap is far above what these probes need: no warning.
  ASSERT_LT(2 * load.substeps, o.objective.step.max_substeps);
  EXPECT_FALSE(mentions_substeps(quiet.warnings)) << quiet.BriefReport();
  // A cap just above the need: the same fit, now at the edge of what the driver may take.
  o.objective.step.max_substeps = load.substeps + load.substeps / 2;
  const CalibrationSummary tight = calibrate(d, o);
  ASSERT_TRUE(tight.fit.converged) << tight.fit.report;
  EXPECT_TRUE(mentions_substeps(tight.warnings)) << tight.BriefReport();
}

// Objective::tally counts every evaluation, the failed ones, and those failed because a
// prediction needed more substeps than the cap: values alone, a Jacobian of Jets, Ceres's cost
// function; a failure of another kind (a substep below min_fraction) is not on the limit.
TEST(DriverLoad, TallyCountsTheEvaluationsThatFailOnTheCap) {
  const auto law = law_with("elastoplastic_fabric", testing::kElastoplasticTruth);
  const CalibrationData d = plastic_data(*law);
  const std::vector<std::string> labels = labels_of(d);
  const ParameterSpace space(*law, law->parameters(), {"M_ss"});
  const std::vector<double> z = space.to_z(law->parameters());
  const auto objective = [&](const ObjectiveOptions& oo) {
    return Objective("elastoplastic_fabric", d, labels, space, oo);
  };
  const auto expect = [](const EvaluationTally& t, long n, long failed, long on_limit) {
    EXPECT_EQ(t.evaluations, n);
    EXPECT_EQ(t.failed, failed);
    EXPECT_EQ(t.failed_on_limit, on_limit);
  };
  std::vector<double> r(static_cast<std::size_t>(objective({}).num_residuals()));
  Eigen::VectorXd rv;
  Eigen::MatrixXd J;

  ObjectiveOptions roomy;
  const Objective ok = objective(roomy);
  const int need = ok.driver_load(law->parameters()).substeps;
  ASSERT_GT(need, 2);
  ASSERT_TRUE(ok.residuals(z.data(), r.data()));
  ASSERT_TRUE(ok.jacobian(z.data(), &rv, &J));
  expect(ok.tally(), 2, 0, 0);

  // One substep fewer than the stiffest probe needs: every evaluation fails on the cap.
  ObjectiveOptions tight;
  tight.step.max_substeps = need - 1;
  const Objective capped = objective(tight);
  EXPECT_FALSE(capped.residuals(z.data(), r.data()));
  expect(capped.tally(), 1, 1, 1);
  EXPECT_FALSE(capped.jacobian(z.data(), &rv, &J));
  expect(capped.tally(), 2, 2, 2);
  const std::unique_ptr<ceres::CostFunction> f(capped.make_cost_function());
  const double* params[1] = {z.data()};
  EXPECT_FALSE(f->Evaluate(params, r.data(), nullptr));
  expect(capped.tally(), 3, 3, 3);

  // A substep may not be shorter than 0.9 of the increment: the first rejection fails, with
  // the cap far away.
  ObjectiveOptions coarse;
  coarse.step.min_fraction = 0.9;
  coarse.step.tolerance = 1e-12;
  const Objective stiff = objective(coarse);
  EXPECT_FALSE(stiff.residuals(z.data(), r.data()));
  expect(stiff.tally(), 1, 1, 0);
}

// After a failed evaluation a stream of evaluations (FailureHint: one fit's) starts its next
// ones where it failed (that part first, from that probe on), so that trial points failing
// there fail at once: the values and the Jacobian at a point that succeeds are the same bits
// as from an objective that never failed. The hint is the stream's: an evaluation without one,
// or through another cost function, starts at the first part.
TEST(DriverLoad, StartingWhereTheLastEvaluationFailedChangesNoBit) {
  const auto law = law_with("elastoplastic_fabric", testing::kElastoplasticTruth);
  const CalibrationData d = plastic_data(*law);
  const std::vector<std::string> labels = labels_of(d);
  const ParameterSpace space(*law, law->parameters(), {"M_ss"});
  ObjectiveOptions oo;
  const auto need = [&](const std::vector<double>& p) {
    return Objective("elastoplastic_fabric", d, labels, space, oo).driver_load(p).substeps;
  };
  // A smaller M_ss makes the probes stiffer: with the cap between the two needs, the truth
  // evaluates and the stiff point fails on the cap.
  std::vector<double> stiff = law->parameters();
  stiff[static_cast<std::size_t>(law->parameter_index("M_ss"))] = 0.3;
  const int easy_need = need(law->parameters()), stiff_need = need(stiff);
  ASSERT_GT(stiff_need, 2 * easy_need) << "M_ss = 0.3 is not stiffer than the truth";
  oo.step.max_substeps = (easy_need + stiff_need) / 2;
  const Objective fresh("elastoplastic_fabric", d, labels, space, oo);
  const Objective hinted("elastoplastic_fabric", d, labels, space, oo);
  const std::vector<double> z_stiff = space.to_z(stiff), z = space.to_z(law->parameters());
  std::vector<double> r0(static_cast<std::size_t>(fresh.num_residuals())), r1 = r0;
  FailureHint stream;
  ASSERT_EQ(stream.part, FailureHint{}.part);
  ASSERT_FALSE(hinted.residuals(z_stiff.data(), r1.data(), &stream));
  ASSERT_EQ(hinted.tally().failed_on_limit, 1);
  // Not the first part: the next evaluations go in another order.
  ASSERT_GT(stream.part, 0) << "the failure was not kept, or it was in the first part";
  ASSERT_TRUE(fresh.residuals(z.data(), r0.data()));
  ASSERT_TRUE(hinted.residuals(z.data(), r1.data(), &stream));
  EXPECT_EQ(r0, r1);
  // The Jacobian through one cost function (one fit's stream): its failure kept in it.
  const std::unique_ptr<ceres::CostFunction> f0(fresh.make_cost_function()),
      f1(hinted.make_cost_function());
  const int n = fresh.num_parameters();
  std::vector<double> v0(r0.size()), v1(r0.size()), J0(r0.size() * n), J1(J0.size());
  double* j0[1] = {J0.data()};
  double* j1[1] = {J1.data()};
  const double* at_stiff[1] = {z_stiff.data()};
  const double* at[1] = {z.data()};
  ASSERT_FALSE(f1->Evaluate(at_stiff, v1.data(), j1));
  ASSERT_EQ(hinted.tally().failed_on_limit, 2);
  ASSERT_TRUE(f0->Evaluate(at, v0.data(), j0));
  ASSERT_TRUE(f1->Evaluate(at, v1.data(), j1));
  EXPECT_EQ(v0, v1);
  EXPECT_EQ(J0, J1);
}

// The optimum well inside the cap (no warning of the kind above), but a global search over the
// box visits points whose probes need more: calibrate() counts them and says so, and with room
// for every trial point it says nothing. Without the tally the fit's warnings were silent here.
TEST(DriverLoad, CalibrateSaysWhenTrialPointsFailedOnTheCap) {
  const auto law = law_with("elastoplastic_fabric", testing::kElastoplasticTruth);
  const CalibrationData d = plastic_data(*law);
  CalibrationOptions o = m_ss_from_the_truth();
  o.solver.backend = Backend::kGlobal;
  o.solver.global_evaluations = 60;
  o.solver.local_evaluations = 30;
  const std::vector<std::string> labels = labels_of(d);
  const int need =
      Objective(o.model, d, labels, ParameterSpace(*law, law->parameters(), {"M_ss"}), o.objective)
          .driver_load(law->parameters())
          .substeps;
  const auto on_the_way = [](const std::vector<std::string>& warnings) {
    return std::any_of(warnings.begin(), warnings.end(), [](const std::string& w) {
      return w.find("evaluations failed because a prediction needed more than") !=
             std::string::npos;
    });
  };

  o.objective.step.max_substeps = 1000000;
  const CalibrationSummary roomy = calibrate(d, o);
  ASSERT_TRUE(roomy.fit.converged) << roomy.fit.report;
  EXPECT_GT(roomy.evaluations.evaluations, 60);
  EXPECT_EQ(roomy.evaluations.failed_on_limit, 0);
  EXPECT_FALSE(on_the_way(roomy.warnings)) << roomy.BriefReport();

  o.objective.step.max_substeps = 2 * need + 2;  // the optimum needs less than half of it
  const CalibrationSummary tight = calibrate(d, o);
  ASSERT_TRUE(tight.fit.converged) << tight.fit.report;
  EXPECT_NEAR(tight.fit.params[law->parameter_index("M_ss")], 0.45, 1e-4);
  EXPECT_FALSE(mentions_substeps(tight.warnings)) << tight.BriefReport();
  EXPECT_GT(tight.evaluations.failed_on_limit, 0);
  EXPECT_LE(tight.evaluations.failed_on_limit, tight.evaluations.failed);
  EXPECT_TRUE(on_the_way(tight.warnings)) << tight.BriefReport();
}

// Held-out states are a measurement at the fitted parameters: a probe there that needs more
// substeps than the fit's cap allows trial points is still predicted, not reported as "cannot
// be evaluated".
TEST(DriverLoad, HeldOutStatesTakeTheDriversOwnBudget) {
  const auto law = law_with("elastoplastic_fabric", testing::kElastoplasticTruth);
  const CalibrationData d = plastic_data(*law);
  const ParameterSpace space(*law, law->parameters(), {"M_ss"});
  std::string held;
  int held_need = 0, fitted_need = 0;
  for (const auto& s : d.states) {
    const int need = Objective("elastoplastic_fabric", d, {s.label}, space, ObjectiveOptions{})
                         .driver_load(law->parameters())
                         .substeps;
    if (need > held_need) {
      fitted_need = std::max(fitted_need, held_need);
      held_need = need;
      held = s.label;
    } else {
      fitted_need = std::max(fitted_need, need);
    }
  }
  ASSERT_GT(held_need, fitted_need + 2) << "the synthetic states need the same substeps";
  CalibrationOptions o = m_ss_from_the_truth();
  o.holdout = {held};
  o.objective.step.max_substeps = (held_need + fitted_need) / 2;  // the fitted states' need fits
  const CalibrationSummary s = calibrate(d, o);
  ASSERT_TRUE(s.fit.converged) << s.fit.report;
  for (const auto& w : s.warnings)
    EXPECT_EQ(w.find("cannot be evaluated at the held-out states"), std::string::npos) << w;
  bool seen = false;
  for (const auto& st : s.states)
    if (st.label == held) {
      seen = true;
      EXPECT_TRUE(st.held_out);
      EXPECT_GE(st.misfit, 0.0) << "the held-out state was not predicted";
    }
  EXPECT_TRUE(seen);
}

}  // namespace
}  // namespace rendulic::calibration

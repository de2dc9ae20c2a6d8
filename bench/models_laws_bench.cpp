// Benchmarks of the constitutive laws:
// one rate evaluation, one analytic tangent, and one driver-integrated probe increment
// (modified Euler or Bogacki-Shampine 3(2), tolerance 1e-6; docs/models.md "Tolerance") at elastic
// (5e-5) and elasto-plastic (2e-3) amplitudes, from the example states of data/models (DEM scale
// for the elastic laws, sand for hypoplastic_wu).
#include <benchmark/benchmark.h>

#include <string>

#include "rendulic/models/driver.hpp"

namespace rendulic::models {
namespace {

const char* const kLaws[] = {"isotropic_elastic", "anisotropic_elastic", "hypoplastic_wu",
                             "elastoplastic_fabric"};

MaterialState state_for(const Law& law) {
  if (law.name() == "hypoplastic_wu")
    return law.make_state(Eigen::Vector3d(1.0e5, 1.2e5, 1.2e5).asDiagonal(),
                          Eigen::Matrix3d::Zero(), 0.6);
  return law.make_state(Eigen::Vector3d(1.7e9, 2.2e9, 2.2e9).asDiagonal(),
                        Eigen::Vector3d(1.6, 2.2, 2.2).asDiagonal(), 0.82);
}

void BM_Rate(benchmark::State& st) {
  auto law = make_law(kLaws[st.range(0)]);
  const MaterialState s = state_for(*law);
  const Eigen::Matrix3d de = probe_strain(305.26, 2e-3);
  for (auto _ : st) benchmark::DoNotOptimize(law->rate(s, de));
  st.SetLabel(kLaws[st.range(0)]);
  st.counters["increments_per_s"] =
      benchmark::Counter(st.iterations(), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_Rate)->DenseRange(0, 3);

void BM_Tangent(benchmark::State& st) {
  auto law = make_law(kLaws[st.range(0)]);
  const MaterialState s = state_for(*law);
  const Eigen::Matrix3d de = probe_strain(305.26, 2e-3);
  for (auto _ : st) benchmark::DoNotOptimize(law->tangent(s, de));
  st.SetLabel(kLaws[st.range(0)]);
  st.counters["tangents_per_s"] = benchmark::Counter(st.iterations(), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_Tangent)->DenseRange(0, 3);

// range(1): amplitude in units of 1e-5 (5 -> elastic probe, 200 -> elasto-plastic probe);
// range(2): the scheme (0 modified Euler, 2 Bogacki-Shampine: Scheme's order).
void BM_IntegratedProbe(benchmark::State& st) {
  auto law = make_law(kLaws[st.range(0)]);
  const MaterialState s = state_for(*law);
  const Eigen::Matrix3d de = probe_strain(305.26, 1e-5 * st.range(1));
  StepOptions o;
  o.scheme = static_cast<Scheme>(st.range(2));
  int substeps = 0, evaluations = 0;
  for (auto _ : st) {
    const StepResult r = integrate(*law, s, de, o);
    substeps = r.substeps;
    evaluations = r.rate_evaluations;
    benchmark::DoNotOptimize(r.end.stress);
  }
  st.SetLabel(std::string(kLaws[st.range(0)]) + " " + kSchemeNames[st.range(2)]);
  st.counters["increments_per_s"] =
      benchmark::Counter(st.iterations(), benchmark::Counter::kIsRate);
  st.counters["substeps"] = substeps;
  st.counters["rate_evals"] = evaluations;
}
BENCHMARK(BM_IntegratedProbe)->ArgsProduct({{0, 1, 2, 3}, {5, 200}, {0, 2}});

}  // namespace
}  // namespace rendulic::models

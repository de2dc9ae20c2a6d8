// Linear response of the contact network (it should take seconds at N = 9261) and its
// building blocks: pair search and one FIRE iteration's worth of force evaluation are
// reported per particle. The packings are generated once per size (random spheres, w = 3,
// nu = 0.70, FIRE to 1e-9 of the mean contact force; ~1 min of set-up at N = 9261).
#include <benchmark/benchmark.h>

#include <map>

#include "rendulic/dem/linear_response.hpp"
#include "rendulic/dem/probe_campaign.hpp"
#include "rendulic/dem/probe_minimise.hpp"

namespace rendulic::dem {
namespace {

const PackingData& packing(int n, double nu = 0.70) {
  static std::map<std::pair<int, double>, PackingData> cache;
  auto it = cache.find({n, nu});
  if (it == cache.end()) {
    GeneratedPackingOptions g;
    g.n = n;
    g.volume_fraction = nu;
    g.seed = 11;
    g.minimise.force_tolerance = 1e-9;
    it = cache.emplace(std::make_pair(n, nu), generate_packing(g, nullptr)).first;
  }
  return it->second;
}

void BM_LinearResponse(benchmark::State& state) {
  const PackingData& p = packing(static_cast<int>(state.range(0)));
  LinearResponseOptions opt;
  opt.solver = state.range(1) ? LinearSolver::kSimplicialLdlt : LinearSolver::kAuto;
  LinearResponse lr;
  for (auto _ : state) {
    lr = linear_response(p, opt);
    benchmark::DoNotOptimize(lr.stiffness.data());
  }
  if (!lr.ok) state.SkipWithError(lr.message.c_str());
  state.counters["factorisation_s"] = lr.seconds_factorisation;
  state.counters["assembly_s"] = lr.seconds_assembly;
  state.counters["backbone_contacts"] = lr.n_backbone_contacts;
  state.SetLabel(lr.solver);
}
BENCHMARK(BM_LinearResponse)
    ->Args({1000, 0})
    ->Args({1000, 1})
    ->Args({9261, 0})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);

void BM_FindPairs(benchmark::State& state) {
  const PackingData& p = packing(static_cast<int>(state.range(0)));
  for (auto _ : state) benchmark::DoNotOptimize(find_pairs(p, 0.0).size());
  state.counters["time_per_particle"] = benchmark::Counter(
      static_cast<double>(p.size()),
      benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}
BENCHMARK(BM_FindPairs)->Arg(1000)->Arg(9261)->Unit(benchmark::kMillisecond);

// A 36 x 2 campaign (amplitudes 5e-5 and 2e-3, default rate and relaxation) on a generated
// state at nu = 0.80 (mean overlap ~7 % of <r>, like the mission's states), by method
// (0 dynamic, 1 minimisation, 2 linear response), with all threads over the probes.
void BM_ProbeCampaign(benchmark::State& state) {
  const PackingData& p = packing(static_cast<int>(state.range(0)), 0.80);
  std::vector<double> radii(p.radii.data(), p.radii.data() + p.size());
  const DemSystem sys =
      system_from_positions(p.positions, radii, p.cell.lengths(), SystemOptions{});
  const ProbeOptions opt;
  const std::vector<double> theta = probe_directions(opt.directions);
  double steps = 0.0;
  for (auto _ : state) {
    for (double amplitude : opt.amplitudes) {
      Envelope env;
      switch (state.range(1)) {
        case 0:
          env = dynamic_envelope(sys, amplitude, theta, opt);
          for (std::size_t i = 0; i < env.size(); ++i) {
            steps += env.diagnostics.at("load_steps")[i] + env.diagnostics.at("relax_steps")[i];
          }
          break;
        case 1:
          env = minimisation_envelope(sys, amplitude, theta, opt);
          break;
        default:
          env = linear_response_envelope(sys, amplitude, theta, opt);
      }
      benchmark::DoNotOptimize(env.d_stress.data());
    }
  }
  state.SetLabel(state.range(1) == 0   ? "dynamic"
                 : state.range(1) == 1 ? "minimisation"
                                       : "linear_response");
  state.counters["probes"] = 2.0 * static_cast<double>(theta.size());
  state.counters["dem_steps_per_probe"] = steps / (2.0 * static_cast<double>(theta.size()));
}
BENCHMARK(BM_ProbeCampaign)
    ->Args({1000, 2})
    ->Args({1000, 1})
    ->Args({1000, 0})
    ->Unit(benchmark::kSecond)
    ->UseRealTime()
    ->Iterations(1);

}  // namespace
}  // namespace rendulic::dem

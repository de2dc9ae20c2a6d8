// Linear response of the contact network (issue 4 item 3: "seconds at N = 9261") and its
// building blocks: pair search and one FIRE iteration's worth of force evaluation are
// reported per particle. The packings are generated once per size (random spheres, w = 3,
// nu = 0.70, FIRE to 1e-9 of the mean contact force; ~1 min of set-up at N = 9261).
#include <benchmark/benchmark.h>

#include <map>

#include "rendulic/dem/linear_response.hpp"
#include "rendulic/dem/probe_minimise.hpp"

namespace rendulic::dem {
namespace {

const PackingData& packing(int n) {
  static std::map<int, PackingData> cache;
  auto it = cache.find(n);
  if (it == cache.end()) {
    GeneratedPackingOptions g;
    g.n = n;
    g.volume_fraction = 0.70;
    g.seed = 11;
    g.minimise.force_tolerance = 1e-9;
    it = cache.emplace(n, generate_packing(g, nullptr)).first;
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

}  // namespace
}  // namespace rendulic::dem

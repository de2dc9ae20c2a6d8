// Google Benchmarks of the DEM hot path: the NormalContact kernel alone, and whole steps
// (contact loop + integrator + list upkeep) on standard states with a fixed team, reported as
// ns per particle-step. The whole-pipeline command is `rendulic bench` (docs/performance.md).
#include <benchmark/benchmark.h>
#include <omp.h>

#include <map>
#include <vector>

#include "rendulic/dem/probe_campaign.hpp"
#include "rendulic/dem/probe_minimise.hpp"
#include "rendulic/dem/protocols.hpp"

namespace rendulic::dem {
namespace {

void BM_NormalContactKernel(benchmark::State& state) {
  const NormalContact c{1e8, 1.0};
  std::vector<double> delta(4096), rate(4096);
  Rng rng(1);
  for (std::size_t i = 0; i < delta.size(); ++i) {
    delta[i] = rng.uniform(0, 1e-5);
    rate[i] = rng.uniform(-1e-2, 1e-2);
  }
  for (auto _ : state) {
    double sum = 0;
    for (std::size_t i = 0; i < delta.size(); ++i) sum += c.force(delta[i], rate[i]);
    benchmark::DoNotOptimize(sum);
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(delta.size()));
}
BENCHMARK(BM_NormalContactKernel);

// A packing of n particles at volume fraction nu, prepared as `rendulic bench` does (fast,
// overdamped compression, then relaxed), and switched to the seed material.
DemSystem packing(std::size_t n, double nu) {
  SystemOptions fast;
  fast.material.gamma_b = 10.0;
  GasOptions g;
  g.n_particles = n;
  g.velocity = 0;
  DemSystem s = make_gas(fast, g, 1);
  CompressOptions c;
  c.target_nu = nu;
  c.rate_max = c.rate_min = 3000;
  compress_isotropic(s, c);
  RelaxOptions r;
  r.time_cap = 2e-5;
  relax(s, r);
  return DemSystem::restore(s.save(), SystemOptions{});
}

// Args: volume fraction (percent), threads, particles, friction mu in hundredths (0: the
// frictionless engine; > 0: the same state restored with friction, its springs starting at
// zero, docs/performance.md "Friction"), and the pair loop's form (DemSystem::set_fixed_loop:
// 0 chosen by timing, 1 branchy, 2 compact). Every case times the same steps, 100 to 2100 from
// the state (as `rendulic bench --steps 2000` and bench/lammps_compare.sh): at nu = 0.64 the
// extension unjams the state and later steps are cheaper, so a case left to run for a time
// would be timed on other steps than a slower one (docs/performance.md "The same steps for
// every figure").
void BM_Step(benchmark::State& state) {
  const double nu = state.range(0) / 100.0;
  const int threads = static_cast<int>(state.range(1));
  const std::size_t n = static_cast<std::size_t>(state.range(2));
  const double mu = state.range(3) / 100.0;
  static std::map<std::pair<std::size_t, int>, DemSystem> cache;
  const auto key = std::pair{n, static_cast<int>(state.range(0))};
  if (!cache.count(key)) cache.emplace(key, packing(n, nu));
  SystemOptions options;
  options.material.mu = mu;
  DemSystem s = mu > 0 ? DemSystem::restore(cache.at(key).save(), options) : cache.at(key);
  omp_set_num_threads(threads);
  s.set_fixed_team(threads);  // this many threads, not the team the engine would choose
  s.set_fixed_loop(static_cast<int>(state.range(4)));
  const Eigen::Vector3d D(400.0, -200.0, -200.0);  // strain-controlled extension
  s.advance(100, D);
  for (auto _ : state) s.step(D);
  // items_per_second = particle-steps per second: ns per particle-step = 1e9 / items_per_second.
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(n));
}
BENCHMARK(BM_Step)
    ->Args({64, 1, 9261, 0, 0})
    ->Args({82, 1, 9261, 0, 0})
    ->Args({64, 2, 9261, 0, 0})
    ->Args({82, 2, 9261, 0, 0})
    ->Args({64, 1, 9261, 50, 0})
    ->Args({82, 1, 9261, 50, 0})
    ->Args({64, 2, 9261, 50, 0})
    ->Args({82, 2, 9261, 50, 0})
    // The loop's two forms against N (docs/performance.md "The contact test and the branch
    // predictor").
    ->ArgsProduct({{64, 82}, {1}, {4000, 9261}, {0}, {0, 1, 2}})
    ->Iterations(2000)
    ->Unit(benchmark::kMicrosecond)
    ->UseRealTime();

// The stress of a state (DemSystem::contacts, then the sum): what the isotropic stage's servo
// asks for every 20 steps. Args: volume fraction (percent), threads (the team of the last
// step, which contacts() uses), particles.
void BM_Stress(benchmark::State& state) {
  const double nu = state.range(0) / 100.0;
  const int threads = static_cast<int>(state.range(1));
  const std::size_t n = static_cast<std::size_t>(state.range(2));
  DemSystem s = packing(n, nu);
  omp_set_num_threads(threads);
  s.set_fixed_team(threads);
  s.step(Eigen::Vector3d::Zero());
  for (auto _ : state) benchmark::DoNotOptimize(s.stress());
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(n));
}
BENCHMARK(BM_Stress)
    ->ArgsProduct({{64, 82}, {1, 2}, {1000, 9261}})
    ->Unit(benchmark::kMicrosecond)
    ->UseRealTime();

// The elastic energy (DemSystem::elastic_energy), which relax() asks for every check_every
// steps: args volume fraction (percent), particles, friction mu in hundredths.
void BM_ElasticEnergy(benchmark::State& state) {
  const double nu = state.range(0) / 100.0;
  const std::size_t n = static_cast<std::size_t>(state.range(1));
  SystemOptions o;
  o.material.mu = state.range(2) / 100.0;
  DemSystem s = DemSystem::restore(packing(n, nu).save(), o);
  omp_set_num_threads(1);
  s.set_fixed_team(1);
  for (int k = 0; k < 20; ++k) s.step(Eigen::Vector3d(400, -200, -200));
  for (auto _ : state) benchmark::DoNotOptimize(s.elastic_energy());
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(n));
}
BENCHMARK(BM_ElasticEnergy)
    ->ArgsProduct({{64, 82}, {1000, 9261}, {0, 50}})
    ->Unit(benchmark::kMicrosecond)
    ->UseRealTime();

// One build of the neighbour list (NeighborList::build, the part of a rebuild that searches
// the bins) of a packing after 20 steps of the extension, at the common skin: args volume
// fraction (percent), threads, particles. The engine rebuilds every ~100 steps at nu = 0.82
// (docs/performance.md "The list build in lanes").
void BM_ListBuild(benchmark::State& state) {
  const double nu = state.range(0) / 100.0;
  const int threads = static_cast<int>(state.range(1));
  const std::size_t n = static_cast<std::size_t>(state.range(2));
  DemSystem s = packing(n, nu);
  omp_set_num_threads(1);
  s.set_fixed_team(1);
  for (int k = 0; k < 20; ++k) s.step(Eigen::Vector3d(400, -200, -200));
  const double skin = s.options().skin * s.options().material.r_mean;
  const Eigen::Vector3d L = s.cell().lengths();
  NeighborList list;
  for (auto _ : state) {
    list.build(s.particles(), L, skin, std::vector<double>(n, 0.5 * skin), threads);
    benchmark::DoNotOptimize(list.index.data());
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(n));
}
BENCHMARK(BM_ListBuild)
    ->ArgsProduct({{64, 82}, {1, 2}, {9261}})
    ->Unit(benchmark::kMicrosecond)
    ->UseRealTime();

// FIRE at fixed cell (minimise_energy), as the probes' relaxation tail, the minimisation probes
// and the states at rest run it: a packing after 20 steps of the extension brought to its
// minimum, an affine strain of `amplitude` (ppm, along the extension), then a fixed number of
// iterations (a minimisation probe). Args:
// volume fraction (percent), particles, amplitude in ppm. items = particle-iterations.
void BM_Minimise(benchmark::State& state) {
  const double nu = state.range(0) / 100.0;
  const std::size_t n = static_cast<std::size_t>(state.range(1));
  const double amplitude = static_cast<double>(state.range(2)) * 1e-6;
  static std::map<std::pair<std::size_t, int>, PackingData> cache;
  const auto key = std::pair{n, static_cast<int>(state.range(0))};
  MinimiseOptions o;
  o.k = SystemOptions{}.material.k;
  if (!cache.count(key)) {
    DemSystem s = packing(n, nu);
    omp_set_num_threads(1);
    s.set_fixed_team(1);
    for (int k = 0; k < 20; ++k) s.step(Eigen::Vector3d(400, -200, -200));
    PackingData at_rest = packing_of(s);
    minimise_energy(at_rest, o);  // the probes' start: a state at its minimum
    cache.emplace(key, std::move(at_rest));
  }
  PackingData start = cache.at(key);
  const Eigen::Matrix3d eps = (amplitude * Eigen::Vector3d(1.0, -0.5, -0.5)).asDiagonal();
  apply_affine_strain(start, eps);
  o.force_tolerance = 1e-12;  // not reached: every run takes max_iterations
  o.max_iterations = 400;
  std::int64_t iterations = 0, rebuilds = 0;
  for (auto _ : state) {
    PackingData p = start;
    const MinimiseSummary m = minimise_energy(p, o);
    iterations += m.iterations;
    rebuilds += m.pair_rebuilds;
    benchmark::DoNotOptimize(p.positions.data());
  }
  state.SetItemsProcessed(iterations * static_cast<std::int64_t>(n));
  state.counters["iterations_per_rebuild"] =
      static_cast<double>(iterations) / static_cast<double>(std::max<std::int64_t>(rebuilds, 1));
}
BENCHMARK(BM_Minimise)
    ->ArgsProduct({{64, 82}, {1000, 9261}, {50, 20000}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
}  // namespace rendulic::dem

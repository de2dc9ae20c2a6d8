// What the engine's figures depend on besides its code: the host's load latency by working-set
// size (a pointer chase, one dependent load per cache line) and the round trip of a cache line
// between two cores (a ping-pong of two pinned threads). docs/performance.md "The engine
// against N on this host" reads them: ns per particle-step rises with N where the step's data
// leaves a core's L2, and a team of two pays per line that crosses between its cores, so that
// engine figures from two hosts compare only with these beside them.
// Run: build/bench/host_bench
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <numeric>
#include <optional>
#include <random>
#include <vector>

#include "rendulic/dem/team.hpp"

namespace {

// One pointer per 64-byte line, the lines visited in a random cycle: each load waits for the
// one before, so the time per load is the latency of the level the working set fits in.
void BM_ChaseLatency(benchmark::State& state) {
  const std::size_t lines = static_cast<std::size_t>(state.range(0)) * 1024 / 64;
  std::vector<std::size_t> order(lines);
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::shuffle(order.begin() + 1, order.end(), std::mt19937_64(1));
  struct alignas(64) Line {
    const Line* next;
  };
  std::vector<Line> ring(lines);
  for (std::size_t k = 0; k < lines; ++k) ring[order[k]].next = &ring[order[(k + 1) % lines]];
  const Line* p = &ring[order[0]];
  constexpr std::int64_t kLoads = 1 << 16;
  for (auto _ : state) {
    for (std::int64_t k = 0; k < kLoads; ++k) p = p->next;
    benchmark::DoNotOptimize(p);
  }
  state.counters["ns_per_load"] =
      benchmark::Counter(static_cast<double>(state.iterations() * kLoads),
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}
BENCHMARK(BM_ChaseLatency)->RangeMultiplier(2)->Range(16, 64 * 1024)->ArgName("KiB");

// A counter line passed between two cores (rendulic::dem::core_round_trip_ns, which `rendulic
// bench` reports beside its figures), about 10 ms per iteration.
void BM_CoreToCoreRoundTrip(benchmark::State& state) {
  double sum = 0;
  int n = 0;
  for (auto _ : state) {
    const std::optional<double> trip = rendulic::dem::core_round_trip_ns(0.01);
    if (!trip) {
      state.SkipWithError("needs two CPUs it may be pinned to");
      return;
    }
    sum += *trip;
    ++n;
  }
  state.counters["ns_per_round_trip"] = sum / n;
}
BENCHMARK(BM_CoreToCoreRoundTrip)->UseRealTime();

}  // namespace

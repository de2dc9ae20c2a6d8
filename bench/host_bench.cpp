// What the engine's figures depend on besides its code: the host's load latency by working-set
// size (a pointer chase, one dependent load per cache line) and the round trip of a cache line
// between two cores (a ping-pong of two pinned threads). docs/performance.md "The engine
// against N on this host" reads them: ns per particle-step rises with N where the step's data
// leaves a core's L2, and a team of two pays per line that crosses between its cores, so that
// engine figures from two hosts compare only with these beside them.
// Run: build/bench/host_bench
#include <benchmark/benchmark.h>
#include <pthread.h>
#include <sched.h>

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <numeric>
#include <random>
#include <thread>
#include <vector>

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

bool pin(int cpu) {
  cpu_set_t set;
  CPU_ZERO(&set);
  CPU_SET(cpu, &set);
  return pthread_setaffinity_np(pthread_self(), sizeof set, &set) == 0;
}

// A counter line passed between cores 0 and 1: each side waits for the other's increment.
void BM_CoreToCoreRoundTrip(benchmark::State& state) {
  if (std::thread::hardware_concurrency() < 2) {
    state.SkipWithError("needs two cores");
    return;
  }
  alignas(64) std::atomic<std::int64_t> flag{0};
  std::atomic<bool> done{false};
  std::thread other([&] {
    pin(1);
    std::int64_t seen = 0;
    while (!done.load(std::memory_order_relaxed)) {
      const std::int64_t v = flag.load(std::memory_order_acquire);
      if (v != seen && (v & 1)) {
        flag.store(v + 1, std::memory_order_release);
        seen = v + 1;
      }
    }
  });
  pin(0);
  constexpr std::int64_t kTrips = 1 << 14;
  std::int64_t v = 0;
  for (auto _ : state)
    for (std::int64_t k = 0; k < kTrips; ++k) {
      flag.store(++v, std::memory_order_release);
      while (flag.load(std::memory_order_acquire) != v + 1) {
      }
      ++v;
    }
  done.store(true);
  other.join();
  state.counters["ns_per_round_trip"] =
      benchmark::Counter(static_cast<double>(state.iterations() * kTrips),
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}
BENCHMARK(BM_CoreToCoreRoundTrip)->UseRealTime();

}  // namespace

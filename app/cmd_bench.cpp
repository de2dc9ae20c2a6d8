// `rendulic bench [--json]` (interfaces.md, issue 3 item 9): DEM throughput in ns per
// particle-step on the standard states (isotropic nu = 0.64 and nu = 0.82, N = 9261) under
// strain-controlled constant-volume extension, for 1 and 2 threads. The states are prepared
// quickly (fast compression with a strong background damping, then relaxed), which matters
// for timing only through the contact network, not for physics; the timed steps use the
// seed material. Each figure is the best of several repetitions (the machine may be shared).
#include <omp.h>

#include <chrono>
#include <iomanip>
#include <iostream>
#include <memory>
#include <sstream>

#include "commands.hpp"
#include "rendulic/core/errors.hpp"
#include "rendulic/dem/protocols.hpp"

namespace rendulic::app {
namespace {

struct BenchOptions {
  bool json = false;
  std::int64_t n_particles = 9261;
  std::vector<int> threads = {1, 2};
  std::vector<double> volume_fractions = {0.64, 0.82};
  double seconds = 1.0;  // timed wall time per figure and repetition (at least)
  int repetitions = 3;
  std::uint64_t seed = 1;
};

dem::DemSystem prepared_state(const BenchOptions& o, double nu) {
  dem::SystemOptions fast;
  fast.material.gamma_b = 10.0;  // overdamped preparation: no heating, quick rest
  dem::GasOptions g;
  g.n_particles = static_cast<std::size_t>(o.n_particles);
  g.velocity = 0.0;
  dem::DemSystem s = dem::make_gas(fast, g, o.seed);
  dem::CompressOptions c;
  c.target_nu = nu;
  c.rate_max = c.rate_min = 3000.0;
  dem::compress_isotropic(s, c);
  dem::RelaxOptions r;
  r.time_cap = 2e-5;
  dem::relax(s, r);
  return dem::DemSystem::restore(s.save(), dem::SystemOptions{});
}

double time_steps(const dem::DemSystem& base, int threads, const BenchOptions& o) {
  omp_set_num_threads(threads);
  const Eigen::Vector3d D(400.0, -200.0, -200.0);  // the quick scenario's path rate
  double best = 1e300;
  for (int rep = 0; rep < o.repetitions; ++rep) {
    dem::DemSystem s = base;
    s.advance(20, D);  // warm caches and the thread pool
    std::int64_t steps = 0;
    const auto t0 = std::chrono::steady_clock::now();
    double el = 0;
    while (el < o.seconds) {
      s.advance(50, D);
      steps += 50;
      el = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    }
    best = std::min(
        best, el * 1e9 / (static_cast<double>(steps) * static_cast<double>(s.particles().size())));
  }
  return best;
}

}  // namespace

Subcommand add_bench(CLI::App& parent) {
  auto o = std::make_shared<BenchOptions>();
  auto* sub = parent.add_subcommand(
      "bench", "DEM throughput (ns per particle-step) on the standard states, 1 and 2 threads");
  sub->add_flag("--json", o->json,
                "print a JSON list of {volume_fraction, threads, n_particles, "
                "ns_per_particle_step}");
  sub->add_option("--particles", o->n_particles, "number of particles")
      ->capture_default_str()
      ->check(CLI::Range(std::int64_t{100}, std::int64_t{10000000}));
  sub->add_option("--threads", o->threads, "thread counts to time")
      ->capture_default_str()
      ->check(CLI::Range(1, 1024));
  sub->add_option("--seconds", o->seconds, "timed wall time per figure and repetition")
      ->capture_default_str()
      ->check(CLI::Range(0.01, 600.0));
  sub->add_option("--repetitions", o->repetitions, "repetitions (the best is reported)")
      ->capture_default_str()
      ->check(CLI::Range(1, 100));
  return {sub, [o]() -> int {
            std::ostringstream json;
            json << "[";
            bool first = true;
            if (!o->json)
              std::cout << "volume_fraction  threads  n_particles  ns_per_particle_step\n";
            for (double nu : o->volume_fractions) {
              if (!o->json) std::cerr << "bench: preparing nu = " << nu << " ...\n";
              const dem::DemSystem state = prepared_state(*o, nu);
              for (int t : o->threads) {
                const double ns = time_steps(state, t, *o);
                if (o->json) {
                  json << (first ? "" : ",") << "{\"volume_fraction\":" << nu
                       << ",\"threads\":" << t << ",\"n_particles\":" << o->n_particles
                       << ",\"ns_per_particle_step\":" << std::setprecision(4) << ns << "}";
                  first = false;
                } else {
                  std::cout << std::setw(15) << nu << std::setw(9) << t << std::setw(13)
                            << o->n_particles << std::setw(22) << std::setprecision(4) << ns
                            << "\n";
                }
              }
            }
            if (o->json) std::cout << json.str() << "]\n";
            return 0;
          }};
}

}  // namespace rendulic::app

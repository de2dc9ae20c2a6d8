// `rendulic bench [--json] [--load] [--phases] [--lammps DIR]` (docs/performance.md): DEM
// throughput in ns per particle-step on the standard states (isotropic nu = 0.64 and nu = 0.82, N =
// 9261) under strain-controlled constant-volume extension, for fixed teams of 1 and 2 threads and
// for the default setting (the team chosen while running, team.hpp). The states are prepared
// quickly (fast compression with a strong background damping, then relaxed), which matters for
// timing only through the contact network, not for physics; the timed steps use the seed material.
// Every figure of a state times the same steps of the same trajectory: at nu = 0.64 the
// extension unjams the state within ~20 000 steps and a step gets 1.6x cheaper on the way
// (docs/performance.md "The same steps for every figure"), so a faster setting that ran further
// in a fixed wall time was timed on cheaper steps. The settings alternate in rounds; idle
// figures are the best round (the machine may be shared). With --load every figure is taken a
// second time beside a busy loop in a child process (a browser, another job or a second MPI
// rank on a user's machine); loaded figures are the mean over the rounds, since the waits for a
// descheduled thread are what they measure. --lammps writes the same states as LAMMPS data
// files, and the timed contact laws as LAMMPS pair lines, for bench/lammps_compare.sh. Before
// each round and after the last it measures the round trip of a cache line between two cores
// (team.hpp), which a team of two pays for and a VM may change by the minute. --phases runs each
// setting once more with the engine's phase clock (DemSystem::set_phase_timing) and says where
// each thread's step goes (docs/performance.md "Where a team's step goes").
#include <omp.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <utility>

#include "cli_options.hpp"
#include "commands.hpp"
#include "packing_system.hpp"
#include "rendulic/core/errors.hpp"
#include "rendulic/core/packing_file.hpp"
#include "rendulic/core/statistics.hpp"
#include "rendulic/core/text_file.hpp"
#include "rendulic/dem/contact.hpp"
#include "rendulic/dem/protocols.hpp"
#include "rendulic/dem/team.hpp"

namespace rendulic::app {
namespace {

struct BenchOptions {
  bool json = false;
  bool load = false;
  bool phases = false;
  std::string lammps_dir;
  std::int64_t n_particles = 9261;
  std::vector<int> threads = {1, 2};
  std::vector<double> volume_fractions = {0.64, 0.82};
  double seconds = 1.0;         // the state's first timed run (at least); sets the steps
  std::int64_t steps = 0;       // > 0: the steps every figure times instead
  double friction = 0;          // > 0: also 1 thread with this mu on the same states
  double rolling_friction = 0;  // > 0 (with friction): also with this mu_r
  int repetitions = 3;
  std::uint64_t seed = 1;
};

// The busy loop of the loaded figures: a child process that spins until killed. It dies with
// the parent (PR_SET_PDEATHSIG), and an interrupt or termination of the parent kills it first.
volatile sig_atomic_t g_busy_pid = 0;

void kill_busy_and_reraise(int sig) {
  if (g_busy_pid > 0) kill(static_cast<pid_t>(g_busy_pid), SIGKILL);
  signal(sig, SIG_DFL);
  raise(sig);
}

class BusyLoop {
 public:
  BusyLoop() {
    const pid_t parent = getpid();
    pid_ = fork();
    if (pid_ < 0) throw std::runtime_error("bench --load: cannot start the busy process");
    if (pid_ == 0) {
      prctl(PR_SET_PDEATHSIG, SIGKILL);
      if (getppid() != parent) _exit(0);
      volatile unsigned long spin = 0;
      for (;;) spin = spin + 1;
    }
    g_busy_pid = pid_;
    old_int_ = signal(SIGINT, kill_busy_and_reraise);
    old_term_ = signal(SIGTERM, kill_busy_and_reraise);
    usleep(100000);  // let the scheduler place it before anything is timed
  }
  BusyLoop(const BusyLoop&) = delete;
  BusyLoop& operator=(const BusyLoop&) = delete;
  ~BusyLoop() {
    kill(pid_, SIGKILL);
    waitpid(pid_, nullptr, 0);
    g_busy_pid = 0;
    signal(SIGINT, old_int_);
    signal(SIGTERM, old_term_);
  }

 private:
  pid_t pid_ = -1;
  void (*old_int_)(int) = SIG_DFL;
  void (*old_term_)(int) = SIG_DFL;
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

const Eigen::Vector3d kRate(400.0, -200.0, -200.0);  // the quick scenario's path rate
// A run stops at this factor of the first run's wall time even short of the state's steps: a
// setting that slow (a team whose member a busy process deschedules) needs no exact span.
constexpr double kCapFactor = 20.0;

// Steps before every timed run, the same for every figure (LAMMPS's `run 100` in
// bench/lammps_compare.sh): the caches, the thread pool and the list are warm.
constexpr std::int64_t kWarmSteps = 100;

// The steps every figure of a state times (after kWarmSteps from the state), and a cap on a
// run's wall time for a setting far slower than the first (a team beside a busy process).
struct Span {
  std::int64_t steps = 0;  // 0: not yet known (the first run times --seconds and sets it)
  double cap_seconds = 0;
};

// One timed run from the state: `threads` > 0 is a fixed team of that size, 0 the default (the
// team chosen while running, up to all cores; its first windows are part of what it costs).
// Wall and CPU time of the process (a shared machine's fair figure for one thread) per
// particle-step.
struct Run {
  double ns = 0, ns_cpu = 0, seconds = 0, steps = 0;
  std::vector<dem::DemSystem::Phases> phases;  // with `phases`: per thread of the team
};
double cpu_seconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}
Run time_once(const dem::DemSystem& base, int threads, int all_cores, const BenchOptions& o,
              Span& span, bool phases = false) {
  omp_set_num_threads(threads > 0 ? threads : all_cores);
  const double n = static_cast<double>(base.particles().size());
  dem::DemSystem s = base;
  s.set_fixed_team(threads);
  s.advance(kWarmSteps, kRate);
  if (phases) s.set_phase_timing(true);
  const bool first = span.steps == 0;
  std::int64_t steps = 0;
  const double c0 = cpu_seconds();
  const auto t0 = std::chrono::steady_clock::now();
  double el = 0;
  while (first ? el < o.seconds : steps < span.steps && el < span.cap_seconds) {
    const std::int64_t chunk = first ? 50 : std::min<std::int64_t>(50, span.steps - steps);
    s.advance(chunk, kRate);
    steps += chunk;
    el = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }
  if (first) span = {steps, kCapFactor * std::max(el, o.seconds)};
  Run r;
  r.steps = static_cast<double>(steps);
  r.seconds = el;
  r.ns = el * 1e9 / (r.steps * n);
  r.ns_cpu = (cpu_seconds() - c0) * 1e9 / (r.steps * n);
  if (phases) r.phases = s.phases();
  return r;
}

// Where a step's wall time went (--phases), us per step: one object per thread of the team, and
// on thread 0 "other", the wall time no phase holds (the team's fork and join, the step's serial
// parts, the clock reads).
nlohmann::ordered_json phases_json(const Run& r) {
  nlohmann::ordered_json threads = nlohmann::ordered_json::array();
  const double us = 1e6 / r.steps;
  for (std::size_t t = 0; t < r.phases.size(); ++t) {
    const dem::DemSystem::Phases& p = r.phases[t];
    nlohmann::ordered_json row;
    row["thread"] = t;
    row["kick"] = p.kick * us;
    row["wait_kick"] = p.wait_kick * us;
    row["forces"] = p.forces * us;
    row["wait_forces"] = p.wait_forces * us;
    row["finish"] = p.finish * us;
    if (t == 0) {
      row["list"] = p.list * us;
      row["other"] = r.seconds * us -
                     (p.kick + p.wait_kick + p.forces + p.wait_forces + p.finish + p.list) * us;
    }
    threads.push_back(row);
  }
  return threads;
}

// A setting's figure over the rounds: the best and the mean (over all steps), wall, the best in
// CPU time, and each round's wall figure.
struct Figure {
  double best = 1e300, mean = 0, best_cpu = 1e300;
  std::vector<double> rounds;
};
// Every setting once per round from the same state over the same steps (`span`), the order
// reversed every other round, so that the settings share both the trajectory and the machine's
// moments: a VM that moves its vCPUs apart for a minute, or a drift, then shows in every
// setting's figure of that round instead of in one setting's. With `trips`, the cores' round
// trip is measured before each round and after the last (rounds + 1 figures, or none where it
// cannot be measured).
std::vector<Figure> time_rounds(const dem::DemSystem& base, const std::vector<int>& settings,
                                int all_cores, const BenchOptions& o, Span& span,
                                std::vector<double>* trips = nullptr) {
  std::vector<Figure> f(settings.size());
  std::vector<double> seconds(settings.size(), 0), steps(settings.size(), 0);
  auto trip = [&] {
    if (!trips) return;
    if (const std::optional<double> t = dem::core_round_trip_ns()) trips->push_back(*t);
  };
  const std::size_t m = settings.size();
  for (int rep = 0; rep < o.repetitions; ++rep) {
    trip();
    for (std::size_t i = 0; i < m; ++i) {
      const std::size_t k = rep % 2 == 0 ? i : m - 1 - i;
      const Run r = time_once(base, settings[k], all_cores, o, span);
      f[k].best = std::min(f[k].best, r.ns);
      f[k].best_cpu = std::min(f[k].best_cpu, r.ns_cpu);
      f[k].rounds.push_back(r.ns);
      seconds[k] += r.seconds;
      steps[k] += r.steps;
    }
  }
  trip();
  if (trips && trips->size() != static_cast<std::size_t>(o.repetitions) + 1) trips->clear();
  const double n = static_cast<double>(base.particles().size());
  for (std::size_t k = 0; k < m; ++k) f[k].mean = seconds[k] * 1e9 / (steps[k] * n);
  return f;
}

// The default setting's figure against the fastest fixed team's in the same round, the median
// over the rounds: what the team controller (team.hpp) costs or gains, with the host's changes
// between rounds taken out.
double default_against_fastest(const std::vector<int>& settings, const std::vector<Figure>& f) {
  std::vector<double> ratio;
  for (std::size_t r = 0; r < f.front().rounds.size(); ++r) {
    double fastest = 1e300, by_default = 0;
    for (std::size_t k = 0; k < settings.size(); ++k) {
      if (settings[k] > 0)
        fastest = std::min(fastest, f[k].rounds[r]);
      else
        by_default = f[k].rounds[r];
    }
    ratio.push_back(by_default / fastest);
  }
  return median(ratio);
}

// The state as a LAMMPS data file (the writer of `rendulic export`), its time step in the
// title, where bench/lammps_compare.sh reads it.
void write_lammps(const dem::DemSystem& s, const std::filesystem::path& file) {
  std::ostringstream title;
  title << std::setprecision(17) << "rendulic bench state (N = " << s.particles().size()
        << ", nu = " << s.volume_fraction() << ", dt = " << s.dt() << " s)";
  write_lammps_data(file, packing_of_system(s), s.material().density, title.str());
}

// The contact law of a timed system as LAMMPS pair lines (dem::lammps_pair_lines, the one
// statement of the mapping), which bench/lammps_compare.sh includes beside the data file.
void write_lammps_pair(const dem::DemSystem& s, const std::filesystem::path& file) {
  AtomicTextFile out(file, "the LAMMPS pair lines");
  out.stream() << dem::lammps_pair_lines(s.material());
  out.commit();
}

std::filesystem::path lammps_file(const BenchOptions& o, double nu, const char* suffix) {
  std::ostringstream name;
  name << "nu" << std::lround(100 * nu) << suffix;
  return std::filesystem::path(o.lammps_dir) / name.str();
}

}  // namespace

Subcommand add_bench(CLI::App& parent) {
  auto o = std::make_shared<BenchOptions>();
  auto* sub = parent.add_subcommand(
      "bench",
      "DEM throughput (ns per particle-step) on the standard states: fixed teams of 1 and 2 "
      "threads and the default setting; --load adds the same figures beside a busy process");
  sub->add_flag("--json", o->json,
                "print a JSON list of {volume_fraction, threads (0: default), n_particles, steps, "
                "ns_per_particle_step[, ns_per_particle_step_loaded][, core_round_trip_ns_before, "
                "core_round_trip_ns_after, core_round_trip_ns_rounds], "
                "ns_per_particle_step_rounds[, ns_per_particle_step_loaded_rounds][, "
                "phases_us_per_step]}");
  sub->add_flag("--phases", o->phases,
                "after the rounds, one more run of each setting over the same steps that says "
                "where a step's wall time goes, per thread of the team (us per step: kick and "
                "drift, the wait after it, pair forces, the wait after them, finish, list "
                "builds, other); in --json the field phases_us_per_step");
  sub->add_flag("--load", o->load,
                "also time every figure beside a busy loop (a child process), side by side");
  auto* lammps =
      sub->add_option("--lammps", o->lammps_dir,
                      "write the prepared states as LAMMPS data files (nuNN.data) and the timed "
                      "contact laws as LAMMPS pair lines (nuNN.pair; with --friction also "
                      "nuNN-friction.pair) into DIR (bench/lammps_compare.sh)");
  sub->add_option("--particles", o->n_particles, "number of particles")
      ->capture_default_str()
      ->check(integer_in_range(100, 10000000));
  sub->add_option("--threads", o->threads,
                  "fixed team sizes to time, distinct (--threads 1 2 or 1,2; the default is "
                  "added)")
      ->capture_default_str()
      ->delimiter(',')
      ->check(integer_in_range(1, kMaxThreads));
  CLI::Option* seconds = sub->add_option("--seconds", o->seconds,
                                         "wall time of each state's first timed run, whose "
                                         "steps every figure of the state then times")
                             ->capture_default_str()
                             ->check(real_in_range(0.01, 600.0));
  // Both given, --steps won without a word and --seconds was ignored.
  sub->add_option("--steps", o->steps,
                  "the steps every figure times instead (after 100 warm-up steps, as "
                  "bench/lammps_compare.sh has LAMMPS do)")
      ->check(integer_in_range(1, 100000000))
      ->excludes(seconds);
  sub->add_option("--friction", o->friction,
                  "also time 1 thread with Coulomb friction mu (dem.friction) on the same states, "
                  "beside the frictionless engine, wall and CPU time")
      ->check(real_in_range(0.0, 10.0));
  sub->add_option("--rolling-friction", o->rolling_friction,
                  "with --friction: also time 1 thread with rolling resistance mu_r "
                  "(dem.rolling_friction) on the same states")
      ->check(real_in_range(0.0, 1.0));
  sub->add_option("--repetitions", o->repetitions,
                  "rounds, each timing every setting once (idle: the best is reported; loaded: "
                  "the mean)")
      ->capture_default_str()
      ->check(integer_in_range(1, 100));
  return {
      sub, [o, lammps]() -> int {
        const int all_cores = omp_get_max_threads();
        // An empty DIR wrote nothing and said nothing; a size given twice was timed twice.
        if (lammps->count() > 0 && o->lammps_dir.empty())
          throw InputError("bench --lammps: the folder name is empty");
        std::vector<std::string> sizes;
        for (const int t : o->threads) sizes.push_back(std::to_string(t));
        if (const std::string* again = first_repeat(sizes))
          throw InputError("bench --threads: " + *again + " given twice");
        if (o->rolling_friction > 0 && !(o->friction > 0))
          throw InputError(
              "bench: --rolling-friction needs --friction > 0 (rotations exist only with "
              "friction)");
        make_folders(o->lammps_dir, "--lammps folder");
        std::vector<int> settings = o->threads;
        settings.push_back(0);  // the default
        nlohmann::ordered_json json = nlohmann::ordered_json::array();
        if (!o->json)
          std::cout << "volume_fraction  threads  n_particles  ns_per_particle_step"
                    << (o->load ? "  loaded" : "") << "\n";
        for (double nu : o->volume_fractions) {
          if (!o->json) std::cerr << "bench: preparing nu = " << nu << " ...\n";
          const dem::DemSystem state = prepared_state(*o, nu);
          if (!o->lammps_dir.empty()) {
            write_lammps(state, lammps_file(*o, nu, ".data"));
            write_lammps_pair(state, lammps_file(*o, nu, ".pair"));
          }
          // The idle figures in alternated rounds, the cores' round trip between them: a VM may
          // move its vCPUs apart and back within minutes, and a team of two pays per line that
          // crosses between them. Every figure of the state covers the same steps.
          Span span{o->steps, o->steps > 0 ? 1e300 : 0.0};
          std::vector<double> trips;
          const std::vector<Figure> idle =
              time_rounds(state, settings, all_cores, *o, span, &trips);
          std::vector<Run> phased;
          if (o->phases)
            for (const int t : settings)
              phased.push_back(time_once(state, t, all_cores, *o, span, true));
          std::vector<Figure> loaded;
          if (o->load) {
            BusyLoop busy;
            loaded = time_rounds(state, settings, all_cores, *o, span);
          }
          for (std::size_t k = 0; k < settings.size(); ++k) {
            const int t = settings[k];
            if (o->json) {
              nlohmann::ordered_json row;
              row["volume_fraction"] = nu;
              row["threads"] = t;
              row["n_particles"] = o->n_particles;
              row["steps"] = span.steps;
              row["ns_per_particle_step"] = idle[k].best;
              if (o->load) row["ns_per_particle_step_loaded"] = loaded[k].mean;
              if (!trips.empty()) {
                row["core_round_trip_ns_before"] = trips.front();
                row["core_round_trip_ns_after"] = trips.back();
                row["core_round_trip_ns_rounds"] = trips;
              }
              row["ns_per_particle_step_rounds"] = idle[k].rounds;
              if (o->load) row["ns_per_particle_step_loaded_rounds"] = loaded[k].rounds;
              if (o->phases) row["phases_us_per_step"] = phases_json(phased[k]);
              json.push_back(row);
            } else {
              std::cout << std::setw(15) << nu << std::setw(9)
                        << (t > 0 ? std::to_string(t) : "default") << std::setw(13)
                        << o->n_particles << std::setw(22) << std::setprecision(4) << idle[k].best;
              if (o->load) std::cout << std::setw(8) << std::setprecision(4) << loaded[k].mean;
              std::cout << "\n";
            }
          }
          if (!o->json) {
            std::cout << "  every figure: steps " << kWarmSteps << " to " << kWarmSteps + span.steps
                      << " from the state\n";
            if (!trips.empty()) {
              std::cout << "  round trip between two cores, before / after the idle figures: "
                        << std::setprecision(4) << trips.front() << " / " << trips.back()
                        << " ns\n";
            } else {
              std::cout << "  round trip between two cores: not measured (fewer than two CPUs "
                           "allowed)\n";
            }
            if (o->phases) {
              const std::streamsize precision = std::cout.precision();
              std::cout << "  where a step goes, us per step (one more run of each setting):\n"
                        << "    threads  thread   kick   wait  forces   wait  finish   list  "
                           "other\n";
              for (std::size_t k = 0; k < settings.size(); ++k) {
                const nlohmann::ordered_json rows = phases_json(phased[k]);
                for (const auto& row : rows) {
                  std::cout << "    " << std::setw(7)
                            << (settings[k] > 0 ? std::to_string(settings[k]) : "default")
                            << std::setw(8) << row["thread"].get<int>() << std::fixed
                            << std::setprecision(1);
                  // The columns' widths as the header's.
                  const std::pair<const char*, int> columns[] = {{"kick", 7},
                                                                 {"wait_kick", 7},
                                                                 {"forces", 8},
                                                                 {"wait_forces", 7},
                                                                 {"finish", 8}};
                  for (const auto& [key, width] : columns)
                    std::cout << std::setw(width) << row[key].get<double>();
                  if (row.contains("list"))
                    std::cout << std::setw(7) << row["list"].get<double>() << std::setw(7)
                              << row["other"].get<double>();
                  std::cout << std::defaultfloat << "\n";
                }
              }
              std::cout.precision(precision);
            }
            if (o->repetitions > 1) {
              std::cout << "  idle rounds, ns per particle-step (";
              for (std::size_t k = 0; k < settings.size(); ++k)
                std::cout << (k ? " / " : "")
                          << (settings[k] > 0 ? std::to_string(settings[k]) : "default");
              std::cout << (trips.empty() ? "):\n" : "; round trip before / after, ns):\n");
              for (std::size_t r = 0; r < idle.front().rounds.size(); ++r) {
                std::cout << "    " << r + 1 << ": ";
                for (std::size_t k = 0; k < settings.size(); ++k)
                  std::cout << (k ? " / " : "") << std::setprecision(4) << idle[k].rounds[r];
                if (!trips.empty())
                  std::cout << "; " << std::setprecision(4) << trips[r] << " / " << trips[r + 1];
                std::cout << "\n";
              }
              std::cout << "  default against the fastest fixed team of the same round, median: "
                        << std::setprecision(3) << default_against_fastest(settings, idle) << "x\n";
            }
          }
          if (o->friction > 0) {
            // The same state and steps, frictionless and frictional (springs from zero).
            dem::SystemOptions f;
            f.material.mu = o->friction;
            const dem::DemSystem rough = dem::DemSystem::restore(state.save(), f);
            if (!o->lammps_dir.empty())
              write_lammps_pair(rough, lammps_file(*o, nu, "-friction.pair"));
            const Figure smooth_1 = time_rounds(state, {1}, all_cores, *o, span).front();
            const Figure rough_1 = time_rounds(rough, {1}, all_cores, *o, span).front();
            // And with rolling resistance (its springs from zero too).
            Figure rolling_1;
            if (o->rolling_friction > 0) {
              f.material.mu_r = o->rolling_friction;
              rolling_1 =
                  time_rounds(dem::DemSystem::restore(state.save(), f), {1}, all_cores, *o, span)
                      .front();
            }
            if (o->json) {
              // One row per contact law (rolling_friction only where it is on).
              auto row_of = [&](double mu, double mu_r, const Figure& fig) {
                nlohmann::ordered_json row;
                row["volume_fraction"] = nu;
                row["threads"] = 1;
                row["n_particles"] = o->n_particles;
                row["steps"] = span.steps;
                row["friction"] = mu;
                if (mu_r > 0) row["rolling_friction"] = mu_r;
                row["ns_per_particle_step"] = fig.best;
                row["ns_per_particle_step_cpu"] = fig.best_cpu;
                json.push_back(row);
              };
              row_of(0.0, 0.0, smooth_1);
              row_of(o->friction, 0.0, rough_1);
              if (o->rolling_friction > 0) row_of(o->friction, o->rolling_friction, rolling_1);
            } else {
              std::cout << "  1 thread, ns per particle-step (wall / CPU): frictionless "
                        << std::setprecision(4) << smooth_1.best << " / " << smooth_1.best_cpu
                        << ", friction " << o->friction << ": " << rough_1.best << " / "
                        << rough_1.best_cpu << " (" << std::setprecision(3)
                        << rough_1.best_cpu / smooth_1.best_cpu << "x CPU)\n";
              if (o->rolling_friction > 0)
                std::cout << "  with rolling friction " << o->rolling_friction << ": "
                          << std::setprecision(4) << rolling_1.best << " / " << rolling_1.best_cpu
                          << " (" << std::setprecision(3) << rolling_1.best_cpu / rough_1.best_cpu
                          << "x CPU of the frictional step)\n";
            }
          }
          if (o->load && !o->json && settings.front() == 1)
            std::cout << "  loaded, default against 1 thread: " << std::setprecision(3)
                      << loaded.back().mean / loaded.front().mean << "x\n";
        }
        if (o->json) std::cout << json.dump(2) << "\n";
        omp_set_num_threads(all_cores);
        return 0;
      }};
}

}  // namespace rendulic::app

// The team-size rule and controller of DEM steps (team.hpp). The rule is checked on its own and
// on real systems (which team a step actually used), the controller on synthetic step times:
// a model machine where a team is faster (idle), slower by a descheduled member's time slice
// per step (loaded), or one turning into the other. No wall clock is read. The pair loop's form
// (DemSystem::set_fixed_loop), chosen by a controller of the same kind, is checked on a real
// system: the default tries both forms, never in a step that tries another team size, a fixed
// form and a frictional system never switch. The step's barrier is checked with real threads:
// its memory order, and a late member waited for; and the cores' round trip
// (core_round_trip_ns) with real pinned threads. The phase clock of a step (set_phase_timing)
// changes no bit and accounts every step of every member.
#include "rendulic/dem/team.hpp"

#include <gtest/gtest.h>
#include <omp.h>
#if defined(__linux__)
#include <pthread.h>
#include <sched.h>
#endif

#include <chrono>
#include <functional>
#include <optional>
#include <thread>
#include <vector>

#include "dem_helpers.hpp"

namespace rendulic::dem {
namespace {

TEST(TeamRule, NoTeamWhereAStepCannotPayForIt) {
  // Below 2 kRowsPerBlock a step lasts about as long as its synchronisations.
  for (std::size_t n : {2u, 100u, 300u, 600u, 999u}) {
    EXPECT_EQ(max_team(n, 2), 1) << n;
    EXPECT_EQ(max_team(n, 64), 1) << n;
  }
  EXPECT_EQ(max_team(1000, 2), 2);
  EXPECT_EQ(max_team(9261, 2), 2);
  EXPECT_EQ(max_team(9261, 1), 1);
  EXPECT_EQ(max_team(9261, 0), 1);
}

TEST(TeamRule, NeverMoreThreadsThanTasks) {
  EXPECT_EQ(task_team(64, 8), 8);
  EXPECT_EQ(task_team(2, 8), 2);
  EXPECT_EQ(task_team(3, 1), 1);
  EXPECT_EQ(task_team(4, 0), 1);  // a team of one: OpenMP takes no team of none
  EXPECT_EQ(task_team(0, 1000), omp_get_max_threads());
  EXPECT_EQ(task_team(0, 1), 1);
}

TEST(TeamRule, BlocksArePowersOfTwoGrowingSlowerThanN) {
  std::size_t previous = 1;
  for (std::size_t n = 2; n < 2000000; n = n * 5 / 4 + 1) {
    const std::size_t b = block_count(n);
    EXPECT_EQ(b & (b - 1), 0u) << n;  // equal shares for 2, 4, ... threads
    EXPECT_GE(b, previous) << n;
    EXPECT_LE(b, 64u);
    if (b > 1) {
      EXPECT_GE(n / b, kRowsPerBlock) << n;  // a block is never tiny
    }
    // Never more threads than blocks, never more than given.
    EXPECT_LE(static_cast<std::size_t>(max_team(n, 1000)), b) << n;
    EXPECT_LE(max_team(n, 3), 3);
    previous = b;
  }
  EXPECT_EQ(block_count(1000), 2u);  // quick.toml's N: two threads can share it
  EXPECT_EQ(block_count(9261), 4u);  // paper.toml's
}

// A dilute gas of n particles: cheap steps.
DemSystem dilute_gas(std::size_t n, const SystemOptions& o = {}) {
  GasOptions g;
  g.volume_fraction = 0.3;
  g.n_particles = n;
  return make_gas(o, g, 3);
}

TEST(TeamRule, ASmallSystemStepsOnOneThreadAndALargerOneUsesTheTeam) {
  const int saved = omp_get_max_threads();
  omp_set_num_threads(2);
  DemSystem small = dilute_gas(300);
  small.set_fixed_team(2);  // even when asked for two threads
  small.advance(3, Eigen::Vector3d::Zero());
  EXPECT_EQ(small.team(), 1);
  DemSystem large = dilute_gas(1000);
  large.set_fixed_team(2);
  large.advance(3, Eigen::Vector3d::Zero());
  EXPECT_EQ(large.team(), 2);
  omp_set_num_threads(1);  // one thread available: no team, whatever is asked
  large.advance(1, Eigen::Vector3d::Zero());
  EXPECT_EQ(large.team(), 1);
  omp_set_num_threads(saved);
}

// DemSystem::set_phase_timing (rendulic bench --phases) only reads clocks: the same steps give
// the same bits with it on or off, and it accounts every step of every member of the team.
TEST(PhaseTiming, SameBitsAndEveryStepOfEveryMemberAccounted) {
  const int saved = omp_get_max_threads();
  omp_set_num_threads(2);
  const DemSystem start = dilute_gas(1000);
  const Eigen::Vector3d D(400.0, -200.0, -200.0);
  DemSystem plain = start, timed = start;
  plain.set_fixed_team(2);
  timed.set_fixed_team(2);
  timed.advance(5, D);
  plain.advance(5, D);
  EXPECT_TRUE(timed.phases().empty());  // off by default
  timed.set_phase_timing(true);
  const std::int64_t builds = timed.list_builds();
  constexpr int kSteps = 1500;
  timed.advance(kSteps, D);
  plain.advance(kSteps, D);
  ASSERT_EQ(timed.team(), 2);
  const Particles &a = plain.particles(), &b = timed.particles();
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a.x[i], b.x[i]) << i;
    ASSERT_EQ(a.vy[i], b.vy[i]) << i;
    ASSERT_EQ(a.fz[i], b.fz[i]) << i;
  }
  const std::vector<DemSystem::Phases> p = timed.phases();
  ASSERT_EQ(p.size(), 2u);
  for (const DemSystem::Phases& q : p) {
    EXPECT_EQ(q.steps, kSteps);
    for (const double s : {q.kick, q.wait_kick, q.forces, q.wait_forces, q.finish})
      EXPECT_GT(s, 0.0);
  }
  // The gas is sheared: the list is rebuilt, and only thread 0 accounts for the builds.
  ASSERT_GT(timed.list_builds(), builds);
  EXPECT_GT(p[0].list, 0.0);
  EXPECT_EQ(p[1].list, 0.0);
  timed.set_phase_timing(true);  // clears
  for (const DemSystem::Phases& q : timed.phases()) EXPECT_EQ(q.steps, 0);
  omp_set_num_threads(saved);
}

TEST(LoopForm, TheDefaultTriesBothFormsAFixedOneAndFrictionNever) {
  const int saved = omp_get_max_threads();
  omp_set_num_threads(1);
  const Eigen::Vector3d D = Eigen::Vector3d::Constant(-100.0);
  // The default: the first window (20 ms of steps) is the branchy form, the next tries the
  // compact one. The cap only bounds a broken controller's run.
  DemSystem s = dilute_gas(1000);
  bool seen[2] = {false, false};
  for (int k = 0; k < 200000 && !(seen[0] && seen[1]); ++k) {
    s.step(D);
    seen[s.compact_loop() ? 1 : 0] = true;
  }
  EXPECT_TRUE(seen[0]);
  EXPECT_TRUE(seen[1]);
  EXPECT_GE(s.loop_controller().explorations(), 1);
  // Fixed: the same form at every step, no window explored.
  for (int form : {1, 2}) {
    DemSystem f = dilute_gas(1000);
    f.set_fixed_loop(form);
    for (int k = 0; k < 3000; ++k) {
      f.step(D);
      ASSERT_EQ(f.compact_loop(), form == 2) << k;
    }
    EXPECT_EQ(f.loop_controller().explorations(), 0);
  }
  // Friction has its own loop: the controller is never consulted.
  SystemOptions o;
  o.material.mu = 0.5;
  DemSystem fr = dilute_gas(1000, o);
  for (int k = 0; k < 3000; ++k) fr.step(D);
  EXPECT_FALSE(fr.compact_loop());
  EXPECT_EQ(fr.loop_controller().explorations(), 0);
  omp_set_num_threads(saved);
}

// The team controller and the loop's controller try their alternatives one at a time: a step
// that tries another team size runs the loop's current form, so that the try is compared with
// its baseline on the same loop (both controllers start together, and their first tries used
// to coincide). Needs two threads; the cap only bounds a broken controller's run.
TEST(LoopForm, NeverTriedInTheSameStepAsAnotherTeamSize) {
  const int saved = omp_get_max_threads();
  omp_set_num_threads(2);
  if (omp_get_max_threads() < 2) GTEST_SKIP() << "one thread only: no team to try";
  DemSystem s = dilute_gas(1000);
  const Eigen::Vector3d D = Eigen::Vector3d::Constant(-100.0);
  bool team_tried = false, loop_tried = false;
  for (int k = 0; k < 400000 && !(team_tried && loop_tried); ++k) {
    s.step(D);
    // A controller's current choice changes only to what was just tried, so a step whose team
    // or form differs from the current one after it was a try.
    const bool team_try = s.team() != s.team_controller().current();
    const bool loop_try = (s.compact_loop() ? 2 : 1) != s.loop_controller().current();
    ASSERT_FALSE(team_try && loop_try) << "step " << k;
    team_tried = team_tried || team_try;
    loop_tried = loop_tried || loop_try;
  }
  EXPECT_TRUE(team_tried);
  EXPECT_TRUE(loop_tried);
  omp_set_num_threads(saved);
}

// Runs `steps` steps of a model machine through the controller; cost(size, step) is the step's
// time in seconds. Returns the total time.
double run_model(TeamController& c, int max_size, std::int64_t first, std::int64_t steps,
                 const std::function<double(int, std::int64_t)>& cost, double* at_team = nullptr) {
  double total = 0;
  for (std::int64_t k = first; k < first + steps; ++k) {
    const int size = c.choose(max_size);
    const double s = cost(size, k);
    if (at_team && size > 1) *at_team += s;
    c.record(size, s);
    total += s;
  }
  return total;
}

TEST(TeamController, UsesTheTeamOnAnIdleMachine) {
  TeamController c;
  // N = 1000 on two idle cores: 40 us serial, 24 us with the team.
  auto idle = [](int size, std::int64_t) { return size > 1 ? 24e-6 : 40e-6; };
  const double total = run_model(c, 2, 0, 200000, idle);
  EXPECT_EQ(c.current(), 2);
  // Within 3 % of always using the team (explorations of one thread are rare).
  EXPECT_LT(total, 1.03 * 200000 * 24e-6);
}

TEST(TeamController, DropsTheTeamOnALoadedMachine) {
  TeamController c;
  // A busy process shares a core: every 8th team step waits for a descheduled member (4 ms).
  auto loaded = [](int size, std::int64_t k) {
    return size > 1 ? (k % 8 == 0 ? 4e-3 : 24e-6) : 40e-6;
  };
  double at_team = 0;
  const double total = run_model(c, 2, 0, 200000, loaded, &at_team);
  EXPECT_EQ(c.current(), 1);
  // Within 5 % of one thread; the explorations became rare.
  EXPECT_LT(total, 1.05 * 200000 * 40e-6);
  EXPECT_LT(at_team, 0.05 * total);
}

TEST(TeamController, ChecksRarelyWhereAStalledStepIsExpensive) {
  TeamController c;
  // A crowded machine: this process gets a sixth of a core (150 us per serial step) and a
  // descheduled team member comes back after 80 ms.
  auto crowded = [](int size, std::int64_t k) {
    return size > 1 ? (k % 8 == 0 ? 80e-3 : 100e-6) : 150e-6;
  };
  double at_team = 0;
  const double total = run_model(c, 2, 0, 100000, crowded, &at_team);
  EXPECT_EQ(c.current(), 1);
  EXPECT_LT(total, 1.03 * 100000 * 150e-6);  // the checks cost about 1 %, not 6 %
  EXPECT_LE(c.explorations(), 3);
}

TEST(TeamController, FollowsTheLoadWhenItComesAndGoes) {
  TeamController c;
  auto idle = [](int size, std::int64_t) { return size > 1 ? 24e-6 : 40e-6; };
  auto loaded = [](int size, std::int64_t k) {
    return size > 1 ? (k % 8 == 0 ? 4e-3 : 24e-6) : 40e-6;
  };
  run_model(c, 2, 0, 100000, idle);
  EXPECT_EQ(c.current(), 2);
  // Load arrives: the team is dropped within a window or two.
  const double t = run_model(c, 2, 100000, 2000, loaded);
  EXPECT_EQ(c.current(), 1);
  EXPECT_LT(t, 0.2);
  run_model(c, 2, 102000, 100000, loaded);
  // Load leaves: the team comes back at the next exploration (at most kMaxSpacing windows).
  const std::int64_t window = static_cast<std::int64_t>(TeamController::kWindowSeconds / 40e-6);
  run_model(c, 2, 202000, (TeamController::kMaxSpacing + 4) * window, idle);
  EXPECT_EQ(c.current(), 2);
  EXPECT_GE(c.switches(), 3);
}

TEST(TeamController, TriesTheTeamAgainWhenTheStepsGetDearer) {
  TeamController c;
  // A gas (N = 1000, few contacts): 5 us serial, 8 us with the team, which loses and is not
  // tried again for tens of windows. Then the gas is compressed into contacts: 40 us serial,
  // 24 us with the team (quick.toml's preparation).
  auto gas = [](int size, std::int64_t) { return size > 1 ? 8e-6 : 5e-6; };
  auto dense = [](int size, std::int64_t) { return size > 1 ? 24e-6 : 40e-6; };
  run_model(c, 2, 0, 20000, gas);
  EXPECT_EQ(c.current(), 1);
  const std::int64_t tried = c.explorations();
  EXPECT_GE(tried, 1);
  // After a window or two of the dearer steps the team is tried, and kept: 4000 steps cost about
  // two windows more than on the team, not what one thread needs (160 ms).
  const double t = run_model(c, 2, 20000, 4000, dense);
  EXPECT_EQ(c.current(), 2);
  EXPECT_LT(t, 0.75 * 4000 * 40e-6);
}

TEST(TeamController, TriesAgainATeamThatLostByFarWithoutAStall) {
  TeamController c;
  // The gas as above, but the team takes 3x one thread at every step (its list rebuilt every few
  // steps; no step is a descheduled member's time slice): a loss by far, not a stall.
  auto gas = [](int size, std::int64_t) { return size > 1 ? 24e-6 : 8e-6; };
  auto dense = [](int size, std::int64_t) { return size > 1 ? 9e-6 : 14e-6; };
  run_model(c, 2, 0, 5000, gas);  // two windows: the team's try lost by 3x
  EXPECT_EQ(c.current(), 1);
  EXPECT_GE(c.explorations(), 1);
  // Tried again after a window or two of the dearer steps, and kept; left to the try's spacing
  // (about ten windows), the 12000 steps would all run on one thread.
  const double t = run_model(c, 2, 5000, 12000, dense);
  EXPECT_EQ(c.current(), 2);
  EXPECT_LT(t, 0.85 * 12000 * 14e-6);
}

TEST(TeamController, DoesNotTryAStalledTeamAgainForAModestRise) {
  TeamController c;
  // The same compression beside a busy process: every 8th team step waits for a descheduled
  // member (4 ms). The team lost by far in the gas; the steps getting 3x dearer do not make it
  // pay, and it is not tried again within the dense phase.
  auto gas = [](int size, std::int64_t k) { return size > 1 ? (k % 8 == 0 ? 4e-3 : 8e-6) : 5e-6; };
  auto dense = [](int size, std::int64_t k) {
    return size > 1 ? (k % 8 == 0 ? 4e-3 : 10e-6) : 15e-6;
  };
  run_model(c, 2, 0, 20000, gas);
  EXPECT_EQ(c.current(), 1);
  const std::int64_t tried = c.explorations();
  double at_team = 0;
  run_model(c, 2, 20000, 4000, dense, &at_team);
  EXPECT_EQ(c.current(), 1);
  EXPECT_EQ(c.explorations(), tried);
  EXPECT_EQ(at_team, 0.0);
}

TEST(TeamController, ClimbsTheLadderToTheBestSize) {
  TeamController c;
  // Eight cores, three of them busy: five threads would be best; of the ladder 1, 2, 4, 8 the
  // team of four is, and eight is slow (descheduled members).
  auto machine = [](int size, std::int64_t k) {
    if (size == 8) return k % 4 == 0 ? 4e-3 : 10e-6;
    return 80e-6 / size;
  };
  run_model(c, 8, 0, 100000, machine);
  EXPECT_EQ(c.current(), 4);
}

TEST(TeamController, OneThreadAvailableMeansNoChoice) {
  TeamController c;
  EXPECT_EQ(c.choose(1), 1);
  c.record(1, 1.0);
  EXPECT_EQ(c.current(), 1);
  EXPECT_EQ(c.explorations(), 0);
}

// The step's barrier (TeamBarrier): what each member wrote before it, every member reads after
// it, round after round, for teams of 2 to 5 threads, more than this machine's cores, so that
// members are descheduled; a spin of 50 us (not the default's milliseconds) makes waits go to
// sleep as well as spin, and keeps the oversubscribed teams quick.
TEST(TeamBarrier, EveryMemberSeesWhatAllWroteBeforeIt) {
  for (std::size_t team = 2; team <= 5; ++team) {
    TeamBarrier barrier(50e-6);
    constexpr int kRounds = 3000;
    std::vector<std::int64_t> slot(team * 16, -1);  // plain memory, a line per member
    std::vector<int> wrong(team, 0);
    std::vector<std::thread> members;
    for (std::size_t t = 0; t < team; ++t)
      members.emplace_back([&, t] {
        for (int r = 0; r < kRounds; ++r) {
          slot[16 * t] = static_cast<std::int64_t>(r) * 10 + static_cast<std::int64_t>(t);
          barrier.arrive_and_wait(team);
          for (std::size_t u = 0; u < team; ++u)
            if (slot[16 * u] != static_cast<std::int64_t>(r) * 10 + static_cast<std::int64_t>(u))
              ++wrong[t];
          barrier.arrive_and_wait(team);  // nobody writes the next round before all have read
        }
      });
    for (auto& m : members) m.join();
    for (std::size_t t = 0; t < team; ++t) EXPECT_EQ(wrong[t], 0) << "team " << team << ", " << t;
  }
}

// A member that arrives late (descheduled by another process, here asleep for 30 ms): the
// others spin kSpinSeconds, then sleep, and leave only after it has arrived.
TEST(TeamBarrier, WaitsAsleepForALateMember) {
  TeamBarrier barrier;
  using Clock = std::chrono::steady_clock;
  for (int round = 0; round < 3; ++round) {
    Clock::time_point late_arrival, early_leave;
    std::thread late([&] {
      std::this_thread::sleep_for(std::chrono::milliseconds(30));
      late_arrival = Clock::now();
      barrier.arrive_and_wait(2);
    });
    barrier.arrive_and_wait(2);
    early_leave = Clock::now();
    late.join();
    EXPECT_GE(early_leave, late_arrival) << round;
  }
  // 30 ms is six times the spin: the early member went to sleep (in each round unless the
  // scheduler delayed it past the late one's arrival).
  EXPECT_GE(barrier.sleeps(), 1);
}

#if defined(__linux__)
// The cores' round trip `rendulic bench` reports: between the first two CPUs the caller may run
// on, a positive figure, the caller's affinity left as it was; refused where the caller may run
// on one CPU only. The bound is loose on purpose (a partner descheduled by another test costs a
// time slice per trip); what is checked is that a figure is measured, not how fast.
TEST(CoreRoundTrip, MeasuredBetweenTwoAllowedCpusAndRefusedOnOne) {
  cpu_set_t before;
  CPU_ZERO(&before);
  ASSERT_EQ(sched_getaffinity(0, sizeof before, &before), 0);
  const std::optional<double> trip = core_round_trip_ns(0.01);
  if (CPU_COUNT(&before) >= 2) {
    ASSERT_TRUE(trip.has_value());
    EXPECT_GT(*trip, 0.0);
    EXPECT_LT(*trip, 1e8);  // 0.1 s per trip
  } else {
    EXPECT_FALSE(trip.has_value());
  }
  cpu_set_t after;
  CPU_ZERO(&after);
  ASSERT_EQ(sched_getaffinity(0, sizeof after, &after), 0);
  EXPECT_TRUE(CPU_EQUAL(&before, &after));

  std::optional<double> on_one = 1.0;
  bool pinned = false;
  std::thread one([&] {
    cpu_set_t set;
    CPU_ZERO(&set);
    for (int c = 0; c < CPU_SETSIZE; ++c)
      if (CPU_ISSET(c, &before)) {
        CPU_SET(c, &set);
        break;
      }
    pinned = pthread_setaffinity_np(pthread_self(), sizeof set, &set) == 0;
    on_one = core_round_trip_ns(0.01);
  });
  one.join();
  ASSERT_TRUE(pinned);
  EXPECT_FALSE(on_one.has_value());
}
#endif

}  // namespace
}  // namespace rendulic::dem

// How many threads a DEM step uses (docs/performance.md, "Threads on a shared machine").
//
// A step of N = 1000 particles lasts tens of microseconds and needs a few team-wide
// synchronisations; a scheduler time slice lasts milliseconds. On an idle machine a team of
// two pays (the synchronisations cost about a microsecond each), but as soon as another
// process competes for a core, one team member is regularly descheduled and the other waits
// for it at every synchronisation: the step then costs a time slice instead of microseconds.
// Because the engine's results do not depend on the team size (dem_system.hpp), the team can
// be chosen while running: TeamController times windows of steps with the team in use and,
// now and then, with a neighbouring size, and keeps the faster one.
//
// max_team() is the static part of the rule: no team at all where the step is too small to
// pay for its synchronisations, and never more threads than the step has blocks of rows.
// task_team() is the team over independent tasks (probes, states), whose steps run serial.
#pragma once

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <optional>

namespace rendulic::dem {

// Rows (particles) per block of the force loop: the blocks are the unit of parallel work and
// of the thread-count independent reduction (dem_system.hpp). Their number depends on N only.
inline constexpr std::size_t kRowsPerBlock = 500;
// Blocks of the force loop for N particles: a power of two (so that 2, 4, ... threads get equal
// shares), two from 2 kRowsPerBlock particles on, then about sqrt(N / kRowsPerBlock) (capped at
// 64): a block is a slab of the cell, and its partners outside it, which cost a copy and a sum
// each, grow with the number of slabs (N = 9261: 4 % more instructions per step with 4 blocks
// than with one, 8 % with 8).
std::size_t block_count(std::size_t n);
// The largest team a step of n particles may use given `threads` available: 1 below
// 2 kRowsPerBlock particles (a step there lasts about as long as a few synchronisations), at
// most one thread per block.
int max_team(std::size_t n, int threads);
// The team over `tasks` independent tasks (probes, states) given `threads` asked for (0: every
// core OpenMP may use): never more threads than tasks. `--threads 64` with eight probes
// started 64 threads, 56 of them with nothing to do; where a container caps the processes,
// one that cannot start ends the run in libgomp.
int task_team(int threads, std::size_t tasks);

// Chooses the team size step by step from measured step times. Sizes are the ladder 1, 2,
// 4, ..., max. The controller runs windows of at least kWindowSeconds of step time: mostly
// with the current size, sometimes (exploration) with a neighbouring size on the ladder; a
// size that was faster by more than kMargin becomes current. It starts with one thread and
// explores upwards at once (on an idle machine the team is in use after one window).
// Explorations that confirm the current size are spaced twice as far apart each time (up to
// kMaxSpacing windows), and far enough apart that their waste is about kOverhead of the time
// (up to kMaxWasteSpacing windows); a failing exploration is cut short as soon as it has cost
// twice what the current size needs for a minimal window plus kSlackSeconds, so a check of the
// team on a loaded machine costs about one descheduled step (a time slice). When a team gets
// markedly slower than in its previous window (load appeared) the next window explores
// downwards at once; when the current size's steps have got kJump dearer since an
// exploration upwards lost without being stalled by load (by less than 2x, or by more with no
// step as long as kSlackSeconds: a descheduled member costs a time slice, milliseconds), as
// when a gas is compressed into contacts, the larger team is tried after one more window.
class TeamController {
 public:
  static constexpr double kWindowSeconds = 0.02;
  static constexpr int kMinWindowSteps = 4;
  static constexpr double kMargin = 0.05;
  static constexpr int kMaxSpacing = 64;
  static constexpr double kOverhead = 0.01;
  static constexpr int kMaxWasteSpacing = 1024;
  static constexpr double kJump = 1.5;  // a team slower than this factor: explore now
  // A try that has cost this factor of the current size is cut short; one that lost by less
  // lost narrowly (not stalled by load) and may win once the steps get dearer, as may one that
  // lost by more without a step of kSlackSeconds (its team slow at every step, not stalled).
  static constexpr double kLost = 2.0;
  static constexpr double kSlackSeconds = 1e-3;  // waking a sleeping team costs far less

  // Team size for the next step, given the largest allowed (>= 1).
  int choose(int max_size);
  // The step just made with `size` threads took `seconds` (wall, without list builds).
  void record(int size, double seconds);
  int current() const { return max_ > 1 ? ladder_[cur_] : 1; }
  // Windows that explored another size, and switches of the current size (for tests).
  std::int64_t explorations() const { return explorations_; }
  std::int64_t switches() const { return switches_; }

 private:
  void reset(int max_size);
  void close_window();
  void start_exploration(bool up);

  static constexpr int kLadder = 16;
  std::array<int, kLadder> ladder_{};
  std::array<double, kLadder> cost_{};  // seconds per step of the last window of each size
  int sizes_ = 0;                       // entries of ladder_ in use
  int max_ = 0;                         // max_size the ladder was made for
  int cur_ = 0;                         // index of the current size
  int win_ = 0;                         // index of the size of the running window
  double win_seconds_ = 0;
  double win_longest_ = 0;  // the running window's longest step
  int win_steps_ = 0;
  int spacing_ = 1;          // windows of the current size between explorations
  int since_ = 0;            // windows of the current size since the last exploration
  double verdict_cost_ = 0;  // the current size's cost when an exploration upwards lost narrowly
  bool explore_up_ = true;
  std::int64_t explorations_ = 0;
  std::int64_t switches_ = 0;
};

// The barrier inside a step's parallel region. libgomp's `omp barrier` makes a futex_wake
// system call at every release, whether or not a thread sleeps (~145 ns on this project's VM,
// on the critical path of the last thread to arrive); a step of N = 1000 particles on two
// threads has two such barriers in ~8 us. This one spins while it waits, as libgomp does, for
// up to spin_seconds (the default about libgomp's own spin: its 300 000 pauses took 7 ms on this
// project's VM, and a shorter spin made a fixed team beside a busy process 1.4x slower: a
// member asleep is woken late), then sleeps on a futex, and wakes sleepers only when there are
// some. It orders memory as `omp barrier` does: everything a member wrote before
// arrive_and_wait is visible to every member after it. Members of one region call it the same
// number of times with the same team size; copies start fresh (a barrier's state lives only
// inside a region). docs/performance.md "The step's barriers".
class TeamBarrier {
 public:
  static constexpr double kSpinSeconds = 5e-3;

  explicit TeamBarrier(double spin_seconds = kSpinSeconds) : spin_seconds_(spin_seconds) {}
  TeamBarrier(const TeamBarrier& o) noexcept : spin_seconds_(o.spin_seconds_) {}
  TeamBarrier& operator=(const TeamBarrier& o) noexcept {
    spin_seconds_ = o.spin_seconds_;
    return *this;
  }

  void arrive_and_wait(std::size_t team);
  // Waits that went to sleep since construction (for tests).
  std::int64_t sleeps() const { return sleeps_.load(std::memory_order_relaxed); }

 private:
  alignas(64) std::atomic<std::uint32_t> arrived_{0};
  alignas(64) std::atomic<std::uint32_t> generation_{0};
  std::atomic<std::uint32_t> sleepers_{0};
  std::atomic<std::int64_t> sleeps_{0};
  double spin_seconds_;
};

// The round trip of a cache line between the first two CPUs this thread may run on, in ns: two
// threads pinned there pass a counter back and forth for about `seconds`. It is what a team of
// two pays for each line that crosses between its members (a barrier costs about one), and a
// VM may move its vCPUs nearer or further apart from one minute to the next (85-110 ns or
// 287-349 ns on one host: docs/performance.md "An eighth host"), so `rendulic bench` reports it
// beside its figures and bench/host_bench.cpp times it. Nothing when fewer than two CPUs are
// allowed or a thread cannot be pinned (and off Linux). The caller's own affinity is unchanged.
// Meaningless beside a busy process: a descheduled partner makes a trip a time slice.
std::optional<double> core_round_trip_ns(double seconds = 0.05);

}  // namespace rendulic::dem

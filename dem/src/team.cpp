// The team-size rule and controller of DEM steps, the team over independent tasks, the barrier
// inside a step, and the round trip between two cores that a team pays for (team.hpp;
// docs/performance.md).
#include "rendulic/dem/team.hpp"

#if defined(__linux__)
#include <linux/futex.h>
#include <pthread.h>
#include <sched.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <climits>
#endif
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <thread>
#include <vector>

namespace rendulic::dem {

std::size_t block_count(std::size_t n) {
  const double rows = static_cast<double>(n) / static_cast<double>(kRowsPerBlock);
  const double want = std::max(std::min(rows, 2.0), std::sqrt(rows));
  std::size_t b = 1;
  while (b < 64 && static_cast<double>(2 * b) <= want) b *= 2;
  return b;
}

int max_team(std::size_t n, int threads) {
  if (n < 2 * kRowsPerBlock || threads <= 1) return 1;
  return static_cast<int>(std::min<std::size_t>(static_cast<std::size_t>(threads), block_count(n)));
}

int task_team(int threads, std::size_t tasks) {
  const int asked = threads > 0 ? threads : omp_get_max_threads();
  return static_cast<int>(std::clamp<std::size_t>(tasks, 1, static_cast<std::size_t>(asked)));
}

void TeamController::reset(int max_size) {
  max_ = max_size;
  sizes_ = 0;
  for (int s = 1; s < max_size && sizes_ < kLadder - 1; s *= 2) ladder_[sizes_++] = s;
  ladder_[sizes_++] = max_size;
  cost_.fill(0.0);
  cur_ = win_ = 0;
  win_seconds_ = 0;
  win_longest_ = 0;
  win_steps_ = 0;
  spacing_ = 1;
  since_ = 0;
  verdict_cost_ = 0;
  explore_up_ = true;
}

int TeamController::choose(int max_size) {
  if (max_size <= 1) return 1;
  if (max_size != max_) reset(max_size);
  return ladder_[win_];
}

void TeamController::record(int size, double seconds) {
  if (max_ <= 1 || size != ladder_[win_]) return;  // not a step of the running window
  win_seconds_ += seconds;
  win_longest_ = std::max(win_longest_, seconds);
  ++win_steps_;
  const bool full = win_seconds_ >= kWindowSeconds && win_steps_ >= kMinWindowSteps;
  // An exploration that already cost kLost times a minimal window of the current size has lost.
  const bool lost =
      win_ != cur_ && cost_[cur_] > 0 &&
      win_seconds_ > kLost * cost_[cur_] * std::max(win_steps_, kMinWindowSteps) + kSlackSeconds;
  if (full || lost) close_window();
}

void TeamController::start_exploration(bool up) {
  const int next = up ? cur_ + 1 : cur_ - 1;
  if (next < 0 || next >= sizes_) return;
  explore_up_ = up;
  win_ = next;
  ++explorations_;
}

void TeamController::close_window() {
  const double steps = win_steps_;
  const double cost = win_seconds_ / steps;
  const double previous = cost_[win_];
  cost_[win_] = cost;
  const bool stalled = win_longest_ >= kSlackSeconds;
  win_seconds_ = 0;
  win_longest_ = 0;
  win_steps_ = 0;
  if (win_ != cur_) {
    // An exploration: keep the faster size, and after a success look further the same way.
    const bool up = win_ > cur_;
    since_ = 0;
    if (cost < (1.0 - kMargin) * cost_[cur_]) {
      cur_ = win_;
      spacing_ = 1;
      verdict_cost_ = 0;
      ++switches_;
      start_exploration(up);
      if (win_ != cur_) return;
    } else {
      // Check again twice as late, and late enough that explorations cost at most about
      // kOverhead of the time: a descheduled team member can waste a whole time slice, tens of
      // milliseconds on a crowded machine.
      const double waste = (cost - cost_[cur_]) * steps;
      const double due = waste / (kOverhead * kWindowSeconds);
      spacing_ = std::max(std::min(2 * spacing_, kMaxSpacing),
                          static_cast<int>(std::min(due, static_cast<double>(kMaxWasteSpacing))));
      // A narrow loss (under kLost times the current size's cost; a team stalled by load loses
      // by more, and record() cuts it short there) may turn into a win when the steps get dearer,
      // and so may a loss by more without a stalled step: in a dilute gas, whose list is rebuilt
      // every few steps, a team of two took 3x one thread's 8 us at every step (quick.toml,
      // docs/performance.md "The team's first step").
      if (up) verdict_cost_ = cost < kLost * cost_[cur_] || !stalled ? cost_[cur_] : 0.0;
    }
    win_ = cur_;
    return;
  }
  ++since_;
  // Load that appears shows as a jump of a team's cost: try fewer threads now.
  if (cur_ > 0 && previous > 0 && cost > kJump * previous) {
    since_ = 0;
    spacing_ = 1;
    start_exploration(false);
    return;
  }
  // The steps got kJump dearer since a larger team lost narrowly (a gas compressed into
  // contacts: the team's share of a step's work grew, its synchronisations did not), so the
  // spacing that verdict set (up to kMaxWasteSpacing windows, seconds) no longer says what a
  // try would waste. The larger team is tried after the next window, which gives the try a
  // baseline of the dearer steps alone (this one may have begun on cheap ones). A try that
  // loses again sets a new verdict and spacing from its own cost.
  if (verdict_cost_ > 0 && cost > kJump * verdict_cost_ && cur_ + 1 < sizes_) {
    since_ = 0;
    spacing_ = 1;
    verdict_cost_ = 0;
    explore_up_ = false;  // the next exploration alternates, upwards
    return;
  }
  if (since_ < spacing_ || sizes_ < 2) return;
  since_ = 0;
  // Explore a neighbour on the ladder, alternating down and up where both exist.
  if (cur_ == 0)
    start_exploration(true);
  else if (cur_ == sizes_ - 1)
    start_exploration(false);
  else
    start_exploration(!explore_up_);
}

namespace {
// Sleep while *word == expected / wake every sleeper on word: the futex itself on Linux (whose
// kernel rechecks the word, so a wake between our check and the sleep is not lost), C++20's
// atomic wait elsewhere.
void sleep_while_equal(std::atomic<std::uint32_t>& word, std::uint32_t expected) {
#if defined(__linux__)
  syscall(SYS_futex, reinterpret_cast<std::uint32_t*>(&word), FUTEX_WAIT_PRIVATE, expected, nullptr,
          nullptr, 0);
#else
  word.wait(expected, std::memory_order_acquire);
#endif
}
void wake_all(std::atomic<std::uint32_t>& word) {
#if defined(__linux__)
  syscall(SYS_futex, reinterpret_cast<std::uint32_t*>(&word), FUTEX_WAKE_PRIVATE, INT_MAX, nullptr,
          nullptr, 0);
#else
  word.notify_all();
#endif
}
}  // namespace

void TeamBarrier::arrive_and_wait(std::size_t team) {
  const std::uint32_t g = generation_.load(std::memory_order_acquire);
  if (arrived_.fetch_add(1, std::memory_order_acq_rel) + 1 == team) {
    arrived_.store(0, std::memory_order_relaxed);
    // seq_cst store then load, against the sleeper's increment then wait (a Dekker pair): either
    // this sees the sleeper, or the sleeper's wait sees the new generation and returns.
    generation_.store(g + 1, std::memory_order_seq_cst);
    if (sleepers_.load(std::memory_order_seq_cst) > 0) wake_all(generation_);
    return;
  }
  // Spin; read the clock only every 64 pauses (a pause is tens of cycles).
  const auto start = std::chrono::steady_clock::now();
  for (;;) {
    for (int k = 0; k < 64; ++k) {
      if (generation_.load(std::memory_order_acquire) != g) return;
#if defined(__x86_64__) || defined(__i386__)
      __builtin_ia32_pause();  // spin politely: the sibling hyperthread keeps its issue slots
#else
      std::this_thread::yield();
#endif
    }
    if (std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() >
        spin_seconds_)
      break;
  }
  sleepers_.fetch_add(1, std::memory_order_seq_cst);
  sleeps_.fetch_add(1, std::memory_order_relaxed);
  while (generation_.load(std::memory_order_seq_cst) == g) sleep_while_equal(generation_, g);
  sleepers_.fetch_sub(1, std::memory_order_relaxed);
}

std::optional<double> core_round_trip_ns(double seconds) {
#if defined(__linux__)
  cpu_set_t allowed;
  CPU_ZERO(&allowed);
  if (sched_getaffinity(0, sizeof allowed, &allowed) != 0) return std::nullopt;
  std::vector<int> cpus;
  for (int c = 0; c < CPU_SETSIZE && cpus.size() < 2; ++c)
    if (CPU_ISSET(c, &allowed)) cpus.push_back(c);
  if (cpus.size() < 2) return std::nullopt;
  auto pin = [](int cpu) {
    cpu_set_t one;
    CPU_ZERO(&one);
    CPU_SET(cpu, &one);
    return pthread_setaffinity_np(pthread_self(), sizeof one, &one) == 0;
  };
  // The first side makes the counter odd and waits for the second to make it even; both stop
  // when the counter is negative. Each side gives up if its pinning failed.
  alignas(64) std::atomic<std::int64_t> counter{0};
  std::atomic<int> pinned{0};
  std::atomic<bool> failed{false};
  std::int64_t trips = 0;
  double elapsed = 0;
  std::thread second([&] {
    if (!pin(cpus[1])) failed.store(true);
    pinned.fetch_add(1);
    for (std::int64_t seen = 0;;) {
      const std::int64_t v = counter.load(std::memory_order_acquire);
      if (v < 0) return;
      if (v != seen && (v & 1)) {
        counter.store(v + 1, std::memory_order_release);
        seen = v + 1;
      }
    }
  });
  std::thread first([&] {
    if (!pin(cpus[0])) failed.store(true);
    pinned.fetch_add(1);
    while (pinned.load() < 2) {
    }
    if (failed.load()) {
      counter.store(-1, std::memory_order_release);
      return;
    }
    const auto start = std::chrono::steady_clock::now();
    std::int64_t v = 0;
    for (;;) {
      for (int k = 0; k < 1024; ++k) {
        counter.store(++v, std::memory_order_release);
        while (counter.load(std::memory_order_acquire) != v + 1) {
        }
        ++v;
      }
      trips += 1024;
      elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      if (elapsed >= seconds) break;
    }
    counter.store(-1, std::memory_order_release);
  });
  first.join();
  second.join();
  if (failed.load() || trips == 0) return std::nullopt;
  return elapsed / static_cast<double>(trips) * 1e9;
#else
  (void)seconds;
  return std::nullopt;
#endif
}

}  // namespace rendulic::dem

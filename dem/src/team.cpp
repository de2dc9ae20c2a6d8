// The team-size rule and controller of DEM steps (team.hpp; docs/performance.md).
#include "rendulic/dem/team.hpp"

#include <algorithm>
#include <cmath>

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

void TeamController::reset(int max_size) {
  max_ = max_size;
  sizes_ = 0;
  for (int s = 1; s < max_size && sizes_ < kLadder - 1; s *= 2) ladder_[sizes_++] = s;
  ladder_[sizes_++] = max_size;
  cost_.fill(0.0);
  cur_ = win_ = 0;
  win_seconds_ = 0;
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
  win_seconds_ = 0;
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
      // by more, and record() cuts it short there) may turn into a win when the steps get dearer.
      if (up) verdict_cost_ = cost < kLost * cost_[cur_] ? cost_[cur_] : 0.0;
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

}  // namespace rendulic::dem

// Progress lines of the run's stages (progress.hpp; docs/usage.md "Progress and messages").
#include "progress.hpp"

#include <omp.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cmath>

#include "rendulic/core/decimal.hpp"
#include "rendulic/core/errors.hpp"
#include "rendulic/core/log.hpp"

namespace rendulic::app {
namespace {
ProgressObserver g_observer;
std::atomic<bool> g_stop{false};
}  // namespace

void set_progress_observer(ProgressObserver observer) { g_observer = std::move(observer); }
void request_stop() { g_stop.store(true, std::memory_order_relaxed); }
void clear_stop() { g_stop.store(false, std::memory_order_relaxed); }
bool stop_requested() { return g_stop.load(std::memory_order_relaxed); }
void throw_if_stopped() {
  // omp_get_level, not omp_in_parallel: a team of one thread is a parallel region too, and no
  // exception may leave one.
  if (stop_requested() && omp_get_level() == 0) throw Cancelled("stopped on request");
}
std::function<bool()> stop_checker() {
  return [] { return stop_requested(); };
}

std::string human_seconds(double s) {
  constexpr double kYear = 365.25 * 86400;
  if (!std::isfinite(s) || s < 0) return "?";
  const auto two_digits = [](int v) { return (v < 10 ? "0" : "") + std::to_string(v); };
  if (s < 60) return decimal_fixed(s, 0) + " s";
  if (s < 3600) {
    const int m = static_cast<int>(s / 60);
    return std::to_string(m) + " min " + two_digits(static_cast<int>(s - 60 * m)) + " s";
  }
  if (s < 2 * 86400) {
    const int h = static_cast<int>(s / 3600);
    return std::to_string(h) + " h " + two_digits(static_cast<int>((s - 3600 * h) / 60)) + " min";
  }
  if (s < 2 * kYear) return decimal_fixed(s / 86400, 0) + " days";
  return decimal_g(s / kYear, 3) + " years";
}

std::string percent_done(double fraction) {
  std::string text = decimal_fixed(100 * std::clamp(fraction, 0.0, 1.0), 1) + "%";
  return std::string(text.size() < 6 ? 6 - text.size() : 0, ' ') + text;
}

std::string time_left(double fraction, double spent) {
  if (!(fraction > 0) || (fraction <= 1e-3 && spent < kPaceAfter)) return "?";
  const double f = std::min(fraction, 1.0);
  return human_seconds(spent * (1 - f) / f);
}

Progress::Progress(const RunContext& ctx, std::string stage)
    : live_(log::enabled(log::Level::kInfo) && isatty(STDERR_FILENO)),
      lines_(log::enabled(log::Level::kInfo) && !live_),
      every_(ctx.progress_every),
      stage_(std::move(stage)),
      start_(Clock::now()),
      task_start_(start_),
      last_(start_) {
  observe(0.0);  // the observer learns of the stage at once; a stop asked for ends here
}

void Progress::observe(double fraction) {
  if (g_observer) {
    std::string task;
    {
      // The observer runs outside the display's lock, so a slow one (Python) holds up only
      // the thread that called it, and only one call at a time per stage.
      const std::unique_lock<std::mutex> lock(observe_mutex_, std::try_to_lock);
      if (!lock.owns_lock()) return throw_if_stopped();
      const auto now = Clock::now();
      {
        const std::lock_guard<std::mutex> task_lock(mutex_);
        task = task_;
      }
      if (task != observed_task_ ||
          std::chrono::duration<double>(now - observed_).count() >= kObserveEvery) {
        observed_ = now;
        observed_task_ = task;
        g_observer(stage_, task, std::clamp(fraction, 0.0, 1.0));
      }
    }
  }
  throw_if_stopped();
}

Progress::~Progress() {
  if (live_ && shown_) log::clear_live();
}

void Progress::start_task(std::string name) {
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    task_ = std::move(name);
    task_start_ = Clock::now();
  }
  throw_if_stopped();
}

void Progress::operator()(double fraction) {
  if (live_ || lines_) {
    const std::lock_guard<std::mutex> lock(mutex_);
    show_locked(fraction, "", task_start_);
  }
  observe(fraction);
}

void Progress::count(long done, long total) {
  const double fraction = total > 0 ? double(done) / double(total) : 1.0;
  if (live_ || lines_) {
    const std::lock_guard<std::mutex> lock(mutex_);
    // Counted work spans the stage's tasks (the probes of every state): paced from its start.
    show_locked(fraction, std::to_string(done) + "/" + std::to_string(total), start_);
  }
  observe(fraction);
}

double Progress::elapsed() const {
  return std::chrono::duration<double>(Clock::now() - start_).count();
}

void Progress::show_locked(double fraction, const std::string& detail, Clock::time_point from) {
  const auto now = Clock::now();
  const double since_last = std::chrono::duration<double>(now - last_).count();
  // A live line is cheap to redraw; a log line is a line someone scrolls past.
  if (live_ ? (shown_ && since_last < 0.2) : since_last < every_) return;
  last_ = now;
  shown_ = true;
  const double f = std::clamp(fraction, 0.0, 1.0);
  const double spent = std::chrono::duration<double>(now - from).count();
  const std::string left = time_left(f, spent);
  std::string text = "[" + stage_ + "] " + task_ + (detail.empty() ? "" : " " + detail) + " " +
                     percent_done(f) + ", " + human_seconds(elapsed()) + " in stage, about " +
                     left + " left";
  if (live_)
    log::live(text);
  else
    log::info(text);
}

}  // namespace rendulic::app

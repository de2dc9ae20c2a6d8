// Progress of the long stages of `rendulic run` (docs/usage.md "Progress and messages"). On a
// terminal, a live status line (stage, task, percent, time left) redrawn at most five times a
// second; in a log (stderr redirected: a batch job, nohup, CI, a notebook) a plain line at most
// every RunContext::progress_every seconds of work, with the same estimate. Every stage also
// says when it starts and ends (pipeline.cpp), so a log shows each stage even when it is short.
// `--quiet` silences both. Updates may come from several OpenMP threads at once.
//
// Besides the terminal, one observer may follow the progress (the Python module's progress
// callback, docs/python.md), and the work may be asked to stop (its Ctrl-C): this class is
// where every long loop reports, so it is where they learn that they should end.
#pragma once

#include <chrono>
#include <functional>
#include <mutex>
#include <string>

#include "pipeline.hpp"
#include "rendulic/dem/protocols.hpp"

namespace rendulic::app {

// The observer: the stage, its current task and the fraction of that task done, at most every
// kObserveEvery seconds per stage, from whichever thread reported (so it must be thread-safe);
// the stage's start and the first report of each task always reach it, so a task shorter than
// kObserveEvery (the probes of a small state on a fast machine) is seen all the same.
// One per process; set it only while no work runs. An empty function removes it.
using ProgressObserver =
    std::function<void(const std::string& stage, const std::string& task, double fraction)>;
inline constexpr double kObserveEvery = 0.2;
void set_progress_observer(ProgressObserver observer);

// Asks the work in progress to stop (any thread, also a signal handler: it only sets a flag).
// The long loops then throw rendulic::Cancelled at their next report made outside a parallel
// region; a probe campaign skips its remaining probes first (ProbeOptions::stop, from
// stop_checker()). clear_stop() before the next piece of work.
void request_stop();
void clear_stop();
bool stop_requested();
// Throws Cancelled if a stop was requested and no OpenMP parallel region (of any team size) is
// open here.
void throw_if_stopped();
// The check a probe campaign takes (dem::ProbeOptions::stop).
std::function<bool()> stop_checker();

// "12 s", "3 min 05 s", "1 h 02 min", "3 days", "35 years": a duration for people. With a
// decimal point whatever locale the process (a Python session) set, as every number rendulic
// writes (core/decimal.hpp).
std::string human_seconds(double seconds);
// "  2.5%": the progress line's share done, five characters wide, of a fraction in [0, 1].
std::string percent_done(double fraction);
// The time a task still needs if the rest goes at the pace so far ("?" while unknown): from
// 0.1 % done, or from kPaceAfter seconds in however little is done, so that a stage of years (a
// mistyped rate) says so instead of "?" for ever.
inline constexpr double kPaceAfter = 5.0;
std::string time_left(double fraction, double spent_seconds);

class Progress {
 public:
  Progress(const RunContext& ctx, std::string stage);
  ~Progress();
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

  // A new task of the stage: its fraction and time left restart from zero.
  void start_task(std::string name);
  // Fraction of the current task done, in [0, 1].
  void operator()(double fraction);
  // Counted work: `done` of `total` units (probes, states) finished.
  void count(long done, long total);
  // Seconds since the stage began.
  double elapsed() const;
  dem::ProgressFn fn() {
    return [this](double f) { (*this)(f); };
  }

 private:
  using Clock = std::chrono::steady_clock;
  void show_locked(double fraction, const std::string& detail, Clock::time_point from);
  // The observer's share of one report (and the stop check after it).
  void observe(double fraction);

  bool live_;     // a terminal: redraw one line
  bool lines_;    // a log: a plain line now and then
  double every_;  // seconds between plain lines
  std::string stage_, task_;
  Clock::time_point start_, task_start_, last_;
  bool shown_ = false;
  Clock::time_point observed_{};
  std::string observed_task_;  // the task of the observer's last report
  std::mutex observe_mutex_;
  std::mutex mutex_;
};

}  // namespace rendulic::app

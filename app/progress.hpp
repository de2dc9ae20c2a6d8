// Progress of the long stages of `rendulic run` (docs/usage.md "Progress and messages"). On a
// terminal, a live status line (stage, task, percent, time left) redrawn at most five times a
// second; in a log (stderr redirected: a batch job, nohup, CI, a notebook) a plain line at most
// every RunContext::progress_every seconds of work, with the same estimate. Every stage also
// says when it starts and ends (pipeline.cpp), so a log shows each stage even when it is short.
// `--quiet` silences both. Updates may come from several OpenMP threads at once.
#pragma once

#include <chrono>
#include <mutex>
#include <string>

#include "pipeline.hpp"
#include "rendulic/dem/protocols.hpp"

namespace rendulic::app {

// "12 s", "3 min 05 s", "1 h 02 min": a duration for people.
std::string human_seconds(double seconds);

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

  bool live_;     // a terminal: redraw one line
  bool lines_;    // a log: a plain line now and then
  double every_;  // seconds between plain lines
  std::string stage_, task_;
  Clock::time_point start_, task_start_, last_;
  bool shown_ = false;
  std::mutex mutex_;
};

}  // namespace rendulic::app

// How many cores the calibration's fits use at once (docs/calibration.md "Threads"). The two
// starts of a likelihood fit run side by side; an exact Jacobian (objective.cpp) takes a second
// thread only while fewer fits run than the cores allowed, so that the start left alone after
// the other has finished does not leave the second core idle, and two starts never become four
// threads.
#pragma once

namespace rendulic::calibration::cores {

// A running fit (one Ceres run) holds a core for its lifetime. `threads` is the fit's limit
// (SolverOptions::threads; 0: every core of the machine).
class FitSlot {
 public:
  explicit FitSlot(int threads);
  ~FitSlot();
  FitSlot(const FitSlot&) = delete;
  FitSlot& operator=(const FitSlot&) = delete;
};

// The cores a fit with this setting may use (0: the machine's, at least 1).
int limit(int threads);
// Whether a helper thread may start now: fewer fits running (at least the asking thread)
// than the latest fit's limit.
bool core_free();

}  // namespace rendulic::calibration::cores

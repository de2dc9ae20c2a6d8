// The calibration's count of running fits against the cores it may use (cores.hpp;
// docs/calibration.md "Threads").
#include "cores.hpp"

#include <algorithm>
#include <atomic>
#include <thread>

namespace rendulic::calibration::cores {
namespace {
std::atomic<int> running{0};
// The latest fit's limit; before any fit (a Jacobian of the uncertainty step alone) every core.
std::atomic<int> allowed{0};
}  // namespace

int limit(int threads) {
  if (threads > 0) return threads;
  return std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
}

FitSlot::FitSlot(int threads) {
  allowed.store(limit(threads));
  running.fetch_add(1);
}

FitSlot::~FitSlot() { running.fetch_sub(1); }

bool core_free() {
  const int a = allowed.load();
  // The asking thread is busy itself, inside a fit or not.
  return std::max(running.load(), 1) < (a > 0 ? a : limit(0));
}

}  // namespace rendulic::calibration::cores

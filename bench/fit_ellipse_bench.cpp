// Cost of one envelope fit: 36-point ellipse fits with and without the
// probe directions, with and without the covariance, a thin ellipse, a robust fit, the
// line fit, and the automatic shape choice (whose bootstrap dominates its cost).
// Run: build/fit_ellipse_bench --benchmark_min_time=0.5
#include <benchmark/benchmark.h>

#include <cmath>
#include <random>

#include "rendulic/core/conventions.hpp"
#include "rendulic/probes/envelope_fit.hpp"

namespace rendulic {
namespace {

Envelope make(double b, double sigma, bool theta, double a = 1.0, int m = 36) {
  std::mt19937_64 rng(5);
  std::normal_distribution<double> normal(0.0, 1.0);
  Envelope env;
  const double phi = deg_to_rad(35.26);
  for (int k = 0; k < m; ++k) {
    const double t = 0.1 + 2.0 * kPi * k / m;
    const Eigen::Vector2d l(a * std::cos(t), b * std::sin(t));
    const Eigen::Vector2d p(std::cos(phi) * l.x() - std::sin(phi) * l.y(),
                            std::sin(phi) * l.x() + std::cos(phi) * l.y());
    env.response.push_back(p + sigma * Eigen::Vector2d(normal(rng), normal(rng)));
    if (theta) env.theta_deg.push_back(rad_to_deg(t));
  }
  return env;
}

void run(benchmark::State& state, const Envelope& env, FitOptions o) {
  for (auto _ : state) {
    EnvelopeFit f = fit_envelope(env, o);
    benchmark::DoNotOptimize(f.a);
  }
}

FitOptions shape(FitShape s, bool cov = true, FitLoss loss = FitLoss::kNone) {
  FitOptions o;
  o.shape = s;
  o.compute_covariance = cov;
  o.loss = loss;
  return o;
}

void BM_Ellipse36(benchmark::State& st) {
  run(st, make(0.3, 0.01, false), shape(FitShape::kEllipse));
}
void BM_Ellipse36Latent(benchmark::State& st) {
  FitOptions o = shape(FitShape::kEllipse);
  o.method = FitMethod::kLatentAngles;
  run(st, make(0.3, 0.01, false), o);
}
void BM_Ellipse36NoCov(benchmark::State& st) {
  run(st, make(0.3, 0.01, false), shape(FitShape::kEllipse, false));
}
void BM_Ellipse36Theta(benchmark::State& st) {
  run(st, make(0.3, 0.01, true), shape(FitShape::kEllipse));
}
void BM_Ellipse36Thin(benchmark::State& st) {
  run(st, make(0.01, 0.0005, true), shape(FitShape::kEllipse));
}
void BM_Ellipse36Huber(benchmark::State& st) {
  run(st, make(0.3, 0.01, false), shape(FitShape::kEllipse, true, FitLoss::kHuber));
}
void BM_Ellipse36OnNoisyLine(benchmark::State& st) {
  run(st, make(0.0, 0.01, false), shape(FitShape::kEllipse, false));
}
void BM_Line36(benchmark::State& st) { run(st, make(0.0, 0.01, true), shape(FitShape::kLine)); }
void BM_Auto36Ellipse(benchmark::State& st) {
  run(st, make(0.05, 0.005, false), shape(FitShape::kAuto));
}
void BM_Auto36Line(benchmark::State& st) {
  run(st, make(0.0, 0.01, false), shape(FitShape::kAuto));
}

BENCHMARK(BM_Ellipse36)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Ellipse36Latent)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Ellipse36NoCov)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Ellipse36Theta)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Ellipse36Thin)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Ellipse36Huber)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Ellipse36OnNoisyLine)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Line36)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Auto36Ellipse)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Auto36Line)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace rendulic

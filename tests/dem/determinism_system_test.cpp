// Parallel determinism (dem_system.hpp): the force loop's blocks and their reduction order
// depend on N only, so 1, 2 and 3 threads give bitwise the same particles after many steps with
// list rebuilds and a servo (stress-controlled) phase, and so does a run that changes its team
// size from step to step or restarts from a saved state on another thread count. The pair loop's
// two forms (the branchy and the compact one, DemSystem::set_fixed_loop) give the same bits too,
// so the form can be chosen by timing. A system test because two threads on a shared machine
// may wait on each other for seconds.
#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>

#include "dem_helpers.hpp"

namespace rendulic::dem {
namespace {

std::vector<double> flat(const Particles& p) {
  std::vector<double> v;
  for (const auto* a : {&p.x, &p.y, &p.z, &p.vx, &p.vy, &p.vz, &p.fx, &p.fy, &p.fz})
    v.insert(v.end(), a->begin(), a->end());
  return v;
}

// A hot, dense gas of 8000 particles (four blocks, so up to four threads share a step),
// compressed, then driven by a lateral stress servo: rebuilds, collisions and the stress sum of
// the servo steps all take part.
void drive(DemSystem& s, int first, int last) {
  const Eigen::Vector3d D = Eigen::Vector3d::Constant(-3000.0);
  for (int k = first; k < last; ++k) {
    if (k < 400)
      s.step(D);
    else
      s.step(CellControl::drained_triaxial(-100.0, 1e5));
  }
}

DemSystem gas() {
  SystemOptions o;
  GasOptions g;
  g.n_particles = 8000;
  g.volume_fraction = 0.4;
  g.velocity = 50.0;  // fast particles: a rebuild every ~100 steps
  return make_gas(o, g, 5);
}

TEST(Determinism, BitIdenticalOnOneTwoAndThreeThreads) {
  const int saved = omp_get_max_threads();
  ASSERT_GE(block_count(8000), 4u);
  std::vector<std::vector<double>> results;
  std::int64_t builds = 0;
  for (int threads : {1, 2, 3}) {
    omp_set_num_threads(threads);
    DemSystem s = gas();
    s.set_fixed_team(threads);
    drive(s, 0, 600);
    EXPECT_EQ(s.team(), threads);
    results.push_back(flat(s.particles()));
    builds = s.list_builds();
  }
  omp_set_num_threads(saved);
  EXPECT_GE(builds, 5);  // the list was rebuilt along the way
  EXPECT_EQ(results[0], results[1]);
  EXPECT_EQ(results[0], results[2]);
}

TEST(Determinism, ChangingTheTeamWhileRunningOrOnRestartChangesNothing) {
  const int saved = omp_get_max_threads();
  omp_set_num_threads(1);
  DemSystem a = gas();
  drive(a, 0, 600);
  // The same run, its team size changing every few steps, saved and restored half way on
  // another thread count.
  omp_set_num_threads(3);
  DemSystem b = gas();
  for (int k = 0; k < 300; k += 25) {
    b.set_fixed_team(1 + (k / 25) % 3);
    drive(b, k, k + 25);
  }
  const State half = b.save();
  omp_set_num_threads(2);
  DemSystem c = DemSystem::restore(half, b.options());
  c.set_fixed_team(2);
  drive(c, 300, 600);
  omp_set_num_threads(saved);
  EXPECT_EQ(flat(a.particles()), flat(c.particles()));
  EXPECT_EQ(a.cell().lengths(), c.cell().lengths());
}

TEST(Determinism, BothFormsOfThePairLoopGiveTheSameBits) {
  const int saved = omp_get_max_threads();
  std::vector<std::vector<double>> results;
  // Fixed forms on one and two threads, the form chosen by timing, and a form changing every
  // 25 steps: a dilute gas (most entries not touching) compressed, then stress-controlled.
  for (int form : {1, 2, 0, -1})
    for (int threads : {1, 2}) {
      omp_set_num_threads(threads);
      DemSystem s = gas();
      s.set_fixed_team(threads);
      for (int k = 0; k < 600; k += 25) {
        s.set_fixed_loop(form >= 0 ? form : 1 + (k / 25) % 2);
        drive(s, k, k + 25);
        if (form > 0) {
          EXPECT_EQ(s.compact_loop(), form == 2);
        }
      }
      results.push_back(flat(s.particles()));
    }
  omp_set_num_threads(saved);
  for (std::size_t r = 1; r < results.size(); ++r) EXPECT_EQ(results[0], results[r]) << r;
}

// A step keeps positions and forces in the engine's records and fills Particles' arrays only
// when they are read (DemSystem::particles; docs/performance.md "The step's footprint"). Reading
// them at every step (each copy followed by a step, some by a list rebuild), or handing them out
// for editing without changing them, gives the trajectory of a run that never reads them, and
// what is read after a step is what a saved state holds.
TEST(Determinism, ReadingOrHandingOutTheParticlesBetweenStepsChangesNothing) {
  const int saved = omp_get_max_threads();
  omp_set_num_threads(1);
  DemSystem a = gas();
  drive(a, 0, 600);
  DemSystem b = gas();
  DemSystem c = gas();
  double sum = 0;
  for (int k = 0; k < 600; ++k) {
    drive(b, k, k + 1);
    sum += b.particles().x[static_cast<std::size_t>(k)] + b.particles().fx[0];
    if (k % 7 == 0) {
      EXPECT_EQ(flat(b.particles()), flat(b.save().particles));
    }
    drive(c, k, k + 1);
    if (k % 50 == 0) c.mutable_particles();  // no edit: the next step packs the same values
  }
  omp_set_num_threads(saved);
  EXPECT_TRUE(std::isfinite(sum));
  EXPECT_GE(b.list_builds(), 5);
  EXPECT_EQ(flat(a.particles()), flat(b.particles()));
  EXPECT_EQ(flat(a.particles()), flat(c.particles()));
}

// A step that rebuilds the neighbour list copies the records to Particles at the build, then
// computes the new forces: what is read or saved after that step must still be the step's end
// (its forces, not those it started from), or a run restored from it, or continued after an
// unedited mutable_particles(), starts from the wrong forces.
TEST(Determinism, ASaveRightAfterAListRebuildContinuesTheRun) {
  const int saved = omp_get_max_threads();
  omp_set_num_threads(1);
  DemSystem a = gas();
  DemSystem b = gas();
  int k = 0;
  const std::int64_t builds = b.list_builds();
  for (; k < 600 && b.list_builds() == builds; ++k) drive(b, k, k + 1);
  ASSERT_GT(b.list_builds(), builds) << "no rebuild in 600 steps";
  drive(a, 0, k);
  EXPECT_EQ(flat(a.particles()), flat(b.particles()));
  DemSystem c = DemSystem::restore(b.save(), b.options());
  b.mutable_particles();  // no edit: the next step packs the same values
  drive(a, k, k + 50);
  drive(b, k, k + 50);
  drive(c, k, k + 50);
  omp_set_num_threads(saved);
  EXPECT_EQ(flat(a.particles()), flat(b.particles()));
  EXPECT_EQ(flat(a.particles()), flat(c.particles()));
}

// The branchy loop visits each row's contacts first and keeps that order as contacts come and
// go (pair_loop.cpp); its forces at rest, after compression, extension and a small move of
// every particle that made and broke contacts since the rows were ordered, against an
// independent all-pairs sum of the contact law (k delta - gamma v_n) n, v_n from the relative
// velocity D l of the cell's strain rate (minimum image; the cell is more than twice the
// largest pair distance).
TEST(Determinism, ForcesAtRestMatchAnAllPairsSum) {
  const int saved = omp_get_max_threads();
  omp_set_num_threads(1);
  SystemOptions o;
  GasOptions g;
  g.n_particles = 1500;
  g.volume_fraction = 0.4;
  g.velocity = 50.0;
  DemSystem s = make_gas(o, g, 7);
  s.set_fixed_loop(1);
  CompressOptions c;
  c.target_nu = 0.66;
  c.rate_max = c.rate_min = 3000;
  compress_isotropic(s, c);
  const Eigen::Vector3d D(400.0, -200.0, -200.0);
  for (int k = 0; k < 300; ++k) s.step(D);
  // Every particle moved by up to 0.01 <r> (well within the list's skin: the contact count
  // below checks that the list still holds every pair), then the forces at rest by the same
  // loop: rows ordered at the old positions meet contacts made and broken since.
  Particles& q = s.mutable_particles();
  const double r = s.material().r_mean;
  for (std::size_t i = 0; i < q.size(); ++i) {
    q.x[i] += 0.01 * r * std::sin(1.7 * static_cast<double>(i));
    q.y[i] += 0.01 * r * std::sin(2.3 * static_cast<double>(i) + 1.0);
    q.z[i] += 0.01 * r * std::sin(3.1 * static_cast<double>(i) + 2.0);
  }
  s.zero_velocities();
  omp_set_num_threads(saved);
  const Particles& p = s.particles();
  const Eigen::Vector3d L = s.cell().lengths();
  const double k = s.material().k, gamma = s.material().gamma;
  const std::size_t n = p.size();
  std::vector<Eigen::Vector3d> f(n, Eigen::Vector3d::Zero());
  double largest = 0;
  std::size_t contacts = 0;
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = i + 1; j < n; ++j) {
      Eigen::Vector3d l(p.x[i] - p.x[j], p.y[i] - p.y[j], p.z[i] - p.z[j]);
      for (int a = 0; a < 3; ++a) l[a] -= L[a] * std::round(l[a] / L[a]);
      const double d = l.norm(), delta = p.radius[i] + p.radius[j] - d;
      if (delta <= 0) continue;
      // At rest the dashpot still sees the cell's strain rate: v_i - v_j = D l.
      const double rate = l.dot(D.cwiseProduct(l)) / d;
      const Eigen::Vector3d fij = (k * delta - gamma * rate) * l / d;
      f[i] += fij;
      f[j] -= fij;
      largest = std::max(largest, k * delta);
      ++contacts;
    }
  ASSERT_GT(contacts, n);  // a connected packing, not a gas
  ASSERT_EQ(s.contacts().size(), contacts);
  ASSERT_GT(L.minCoeff(), 4.0 * *std::max_element(p.radius.begin(), p.radius.end()));
  for (std::size_t i = 0; i < n; ++i) {
    EXPECT_NEAR(p.fx[i], f[i][0], 1e-10 * largest) << i;
    EXPECT_NEAR(p.fy[i], f[i][1], 1e-10 * largest) << i;
    EXPECT_NEAR(p.fz[i], f[i][2], 1e-10 * largest) << i;
  }
}

// The servo of step(CellControl) reads the stress that the last step summed. A state saved
// during the servo phase carries it, so the restored run continues on the uninterrupted run's
// bits (before, it restarted from a zero stress: the first step drove the lateral axes at the
// servo's largest rate). A servo step after plain steps, which sum no stress, measures it
// now: its D is the control's answer to stress() before the step (before, the stress summed
// at the last measuring step, here the refresh of the system's construction).
TEST(Determinism, TheServoReadsTheLastStepsStressAlsoAfterARestore) {
  const int saved = omp_get_max_threads();
  omp_set_num_threads(1);
  DemSystem a = gas();
  drive(a, 0, 600);
  DemSystem b = gas();
  drive(b, 0, 450);
  DemSystem c = DemSystem::restore(b.save(), b.options());
  drive(c, 450, 600);
  EXPECT_EQ(flat(a.particles()), flat(c.particles()));
  EXPECT_EQ(a.cell().lengths(), c.cell().lengths());

  DemSystem d = gas();
  drive(d, 0, 400);
  const CellControl control = CellControl::drained_triaxial(-100.0, 1e5);
  const Eigen::Vector3d D = control.velocity_gradient(d.stress().diagonal(), d.material().k_star());
  d.step(control);
  omp_set_num_threads(saved);
  EXPECT_EQ(d.last_D(), D);
  EXPECT_NE(D[1], -100.0);  // the lateral axes follow the servo
}

}  // namespace
}  // namespace rendulic::dem

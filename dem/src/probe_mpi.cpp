// Probe campaigns across MPI ranks: the session, the worker loop and the
// task/reply messages of probe_mpi.hpp. Point-to-point messages only, always in the same
// pattern (rank 0 sends one task to every worker, every worker sends exactly one reply,
// success or error), so an error on either side can never leave a rank waiting in a
// collective the others have left. Waits poll with a short sleep instead of blocking in MPI:
// Open MPI's blocking calls spin a core, which would steal it from rank 0's pipeline (the
// workers idle through every non-probe stage) and from the other ranks' probes when the
// ranks are oversubscribed.
#include "rendulic/dem/probe_mpi.hpp"

#include <chrono>
#include <cstdlib>
#include <limits>
#include <thread>

#include "rendulic/dem/probe_options.hpp"

#ifdef RENDULIC_WITH_MPI
// The C API only: the deprecated C++ bindings are not used and would only add warnings.
#define OMPI_SKIP_MPICXX 1
#define MPICH_SKIP_MPICXX 1
#include <mpi.h>
#endif

namespace rendulic::dem {

using detail::ByteReader;
using detail::ByteWriter;

// Archive functions of the task's parts. The structured bindings name every member: adding
// a member to one of these structs fails to compile here until it travels to the workers
// too (a forgotten option would otherwise silently take its default on the workers).
template <class A>
void io(A& a, Particles& p) {
  auto& [x, y, z, vx, vy, vz, fx, fy, fz, radius, inv_mass, wx, wy, wz, tx, ty, tz] = p;
  for (std::vector<double>* v :
       {&x, &y, &z, &vx, &vy, &vz, &fx, &fy, &fz, &radius, &inv_mass, &wx, &wy, &wz, &tx, &ty, &tz})
    a(*v);
}
template <class A>
void io(A& a, State& s) {
  auto& [particles, lengths, strain_E, last_D, time, steps, ref_x, ref_y, ref_z, ref_lengths,
         ref_half_skin, tangential_history, sliding_dissipation, rolling_history, last_stress_diag,
         last_stress_known] = s;
  a(particles), a(lengths), a(strain_E), a(last_D), a(time), a(steps);
  a(ref_x), a(ref_y), a(ref_z), a(ref_lengths), a(ref_half_skin);
  a(tangential_history), a(sliding_dissipation), a(rolling_history);
  a(last_stress_diag), a(last_stress_known);
}
template <class A>
void io(A& a, Material& m) {
  auto& [k, gamma, gamma_b, density, r_mean, w, mu, k_t_ratio, gamma_t_ratio, mu_r, k_r_ratio,
         gamma_r_ratio] = m;
  a(k), a(gamma), a(gamma_b), a(density), a(r_mean), a(w), a(mu), a(k_t_ratio), a(gamma_t_ratio);
  a(mu_r), a(k_r_ratio), a(gamma_r_ratio);
}
template <class A>
void io(A& a, SystemOptions& o) {
  auto& [material, dt_factor, skin] = o;
  a(material), a(dt_factor), a(skin);
}
template <class A>
void io(A& a, RelaxOptions& o) {
  auto& [kinetic_to_elastic, time_cap, check_every] = o;
  a(kinetic_to_elastic), a(time_cap), a(check_every);
}
template <class A>
void io(A& a, MinimiseOptions& o) {
  auto& [k, force_tolerance, max_iterations, skin] = o;
  a(k), a(force_tolerance), a(max_iterations), a(skin);
}
template <class A>
void io(A& a, LinearResponseOptions& o) {
  auto& [k, solver, min_contacts, floppy_tolerance, pivot_tolerance, diagnose_max_dof] = o;
  a(k), a(solver), a(min_contacts), a(floppy_tolerance), a(pivot_tolerance), a(diagnose_max_dof);
}
template <class A>
void io(A& a, ProbeOptions& o) {
  auto& [directions, amplitudes, planes, inertial_number, rate, dt_factor, relax, relax_method,
         relax_fire_from, minimise, linear, threads, probe_done, stop] = o;
  a(directions), a(amplitudes), a(planes), a(inertial_number), a(rate), a(dt_factor), a(relax);
  a(relax_method), a(relax_fire_from), a(minimise);
  a(linear), a(threads);
  // Rank 0's progress display and stop request: not sent, a worker counts nothing and is
  // released by rank 0.
  (void)probe_done, (void)stop;
}

namespace {

// One envelope's task, as sent to the workers.
struct Task {
  std::string method;
  std::string plane;  // the probe plane's name (core/conventions.hpp)
  State state;
  SystemOptions system;
  double amplitude = 0;
  std::vector<double> theta_deg;
  ProbeOptions options;
};
template <class A>
void io(A& a, Task& t) {
  a(t.method), a(t.plane), a(t.state), a(t.system), a(t.amplitude), a(t.theta_deg), a(t.options);
}

// Inside a worker's serve(): the share of the task being computed, and whether its reply has
// been sent (an envelope function that throws before exchange() leaves that to serve()).
struct Serving {
  bool active = false;
  ProbeShare share;
  bool replied = false;
};
Serving g_serving;

#ifdef RENDULIC_WITH_MPI
int g_rank = 0;  // of the session, while there is one
int g_size = 1;

bool launched_by_mpi() {
  for (const char* v : {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_SIZE", "PMI_RANK"})
    if (std::getenv(v)) return true;
  return false;
}

constexpr int kTagTask = 1;
constexpr int kTagStop = 2;
constexpr int kTagReply = 3;
constexpr char kReplyOk = 0;
constexpr char kReplyError = 1;

// Waits for a message from `source` with `tag` (MPI_ANY_TAG: any) without spinning a core.
MPI_Status wait_for(int source, int tag) {
  MPI_Status status;
  int flag = 0;
  auto pause = std::chrono::microseconds(20);
  for (;;) {
    MPI_Iprobe(source, tag, MPI_COMM_WORLD, &flag, &status);
    if (flag) return status;
    std::this_thread::sleep_for(pause);
    if (pause < std::chrono::milliseconds(5)) pause *= 2;
  }
}

std::vector<char> receive(int source, int tag) {
  MPI_Status status = wait_for(source, tag);
  int n = 0;
  MPI_Get_count(&status, MPI_CHAR, &n);
  std::vector<char> bytes(static_cast<std::size_t>(n));
  MPI_Recv(bytes.data(), n, MPI_CHAR, status.MPI_SOURCE, status.MPI_TAG, MPI_COMM_WORLD,
           MPI_STATUS_IGNORE);
  return bytes;
}

void send(std::vector<char>& bytes, int dest, int tag) {
  if (bytes.size() > static_cast<std::size_t>(std::numeric_limits<int>::max()))
    throw std::runtime_error("MPI probe message over 2 GiB");
  MPI_Send(bytes.data(), static_cast<int>(bytes.size()), MPI_CHAR, dest, tag, MPI_COMM_WORLD);
}

void reply(char kind, std::vector<char> payload) {
  payload.insert(payload.begin(), kind);
  send(payload, 0, kTagReply);
  g_serving.replied = true;
}
#endif

}  // namespace

bool built_with_mpi() {
#ifdef RENDULIC_WITH_MPI
  return true;
#else
  return false;
#endif
}

MpiSession::MpiSession() {
#ifdef RENDULIC_WITH_MPI
  int already = 0;
  MPI_Initialized(&already);
  if (already || !launched_by_mpi()) return;
  // MPI is called from the main thread only, outside the OpenMP regions.
  int provided = 0;
  MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided);
  MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
  MPI_Comm_size(MPI_COMM_WORLD, &size_);
  initialised_ = true;
  g_rank = rank_;
  g_size = size_;
#endif
}

MpiSession::~MpiSession() {
#ifdef RENDULIC_WITH_MPI
  if (!initialised_) return;
  if (rank_ == 0) {
    std::vector<char> none;
    for (int r = 1; r < size_; ++r) send(none, r, kTagStop);
  }
  g_rank = 0;
  g_size = 1;
  MPI_Finalize();
#endif
}

void MpiSession::serve(const ShareFn& compute) {
  (void)compute;  // a build without MPI has no workers
#ifdef RENDULIC_WITH_MPI
  if (!initialised_ || rank_ == 0) return;
  for (;;) {
    const MPI_Status status = wait_for(0, MPI_ANY_TAG);
    const std::vector<char> bytes = receive(0, status.MPI_TAG);
    if (status.MPI_TAG == kTagStop) return;
    g_serving = {true, {rank_, size_}, false};
    try {
      Task task;
      ByteReader in(bytes);
      in(task);
      const DemSystem state = DemSystem::restore(task.state, task.system);
      compute(task.method, task.plane, state, task.amplitude, task.theta_deg, task.options);
      if (!g_serving.replied) throw std::runtime_error("a worker computed no probes");
    } catch (const std::exception& e) {
      if (!g_serving.replied) {
        ByteWriter w;
        std::string what = "rank " + std::to_string(rank_) + ": " + e.what();
        w(what);
        reply(kReplyError, std::move(w.bytes()));
      }
    }
    g_serving = {};
  }
#endif
}

namespace detail {

int probe_ranks() {
  if (g_serving.active) return g_serving.share.size;
#ifdef RENDULIC_WITH_MPI
  return g_size;
#else
  return 1;
#endif
}

ProbeTaskScope::ProbeTaskScope(const std::string& method, const std::string& plane,
                               const DemSystem& state, double amplitude,
                               const std::vector<double>& theta_deg, const ProbeOptions& options) {
  if (g_serving.active) {
    share_ = g_serving.share;
    return;
  }
#ifdef RENDULIC_WITH_MPI
  if (g_size > 1 && g_rank == 0) {
    Task task{method, plane, state.save(), state.options(), amplitude, theta_deg, options};
    ByteWriter w;
    w(task);
    for (int r = 1; r < g_size; ++r) send(w.bytes(), r, kTagTask);
    share_ = {0, g_size};
    next_reply_ = 1;
  }
#else
  (void)method, (void)plane, (void)state, (void)amplitude, (void)theta_deg, (void)options;
#endif
}

ProbeTaskScope::~ProbeTaskScope() {
#ifdef RENDULIC_WITH_MPI
  // Rank 0 is leaving with an exception: drop the outstanding replies.
  while (next_reply_ > 0 && next_reply_ < share_.size) receive(next_reply_++, kTagReply);
#endif
}

std::vector<std::vector<char>> ProbeTaskScope::exchange(std::vector<char> mine) {
  std::vector<std::vector<char>> replies;
#ifdef RENDULIC_WITH_MPI
  if (is_worker()) {
    reply(kReplyOk, std::move(mine));
    return replies;
  }
  if (next_reply_ != 1) return replies;
  std::string first_error;
  while (next_reply_ < share_.size) {
    std::vector<char> bytes = receive(next_reply_++, kTagReply);
    if (bytes.empty()) throw std::runtime_error("empty reply from an MPI probe worker");
    if (bytes.front() == kReplyError) {
      std::string what;
      const std::vector<char> text(bytes.begin() + 1, bytes.end());
      ByteReader in(text);
      in(what);
      if (first_error.empty()) first_error = what;
    }
    bytes.erase(bytes.begin());
    replies.push_back(std::move(bytes));
  }
  if (!first_error.empty()) throw std::runtime_error(first_error);
#else
  (void)mine;
#endif
  return replies;
}

}  // namespace detail
}  // namespace rendulic::dem

// Probe campaigns across MPI ranks (docs/physics.md section 5: probes are
// independent and run in parallel). Under `mpirun -np K rendulic run`, rank 0 runs the whole
// pipeline and alone prints and writes files; ranks 1..K-1 serve probe campaigns. For each
// dynamic or minimisation envelope rank 0 sends the task to every worker: the state through
// DemSystem::save() (restore() rebuilds it bit for bit; for dynamic probes it is the reference
// rank 0 has already relaxed), the amplitude, the directions and the ProbeOptions. Every rank
// computes the probes p with p % K == rank (with its OpenMP team) by the very same envelope
// function; the workers send their per-probe records back and rank 0 assembles the envelope
// by the same code as a single process. Each probe is a function of (state, direction,
// options) only, so the envelope is bitwise the same for any rank and thread count.
//
// Without RENDULIC_MPI (or when not launched by an MPI launcher) everything here is the
// single-process case: one rank, nothing sent, nothing initialised. The MPI calls live in
// probe_mpi.cpp only.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <cstring>
#include <functional>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include "rendulic/dem/dem_system.hpp"

namespace rendulic::dem {

struct ProbeOptions;

// True when this build has MPI (cmake -DRENDULIC_MPI=ON).
bool built_with_mpi();

// MPI for one `rendulic run`. MPI is initialised only when an MPI launcher started the
// process (its environment says so: OMPI_COMM_WORLD_SIZE, PMIX_RANK, PMI_SIZE); a plain
// launch stays a single process without touching MPI (no singleton start-up, which costs
// ~0.4 s and forks a daemon). One session per process.
class MpiSession {
 public:
  MpiSession();
  // Rank 0 releases the workers (also when an exception is unwinding), then MPI_Finalize.
  ~MpiSession();
  MpiSession(const MpiSession&) = delete;
  MpiSession& operator=(const MpiSession&) = delete;

  int rank() const { return rank_; }
  int size() const { return size_; }
  // A worker's share of one envelope: dem::compute_worker_share (probe_campaign.hpp), passed
  // in so that the campaigns call this layer and not the other way round.
  // `plane` is the probe plane's name (core/conventions.hpp).
  using ShareFn = std::function<void(
      const std::string& method, const std::string& plane, const DemSystem& state, double amplitude,
      const std::vector<double>& theta_deg, const ProbeOptions& options)>;
  // Ranks != 0: compute shares of the campaigns rank 0 sends until it releases them. Never
  // prints and never writes files; an error of a task is sent back to rank 0, which reports it.
  void serve(const ShareFn& compute);

 private:
  int rank_ = 0;
  int size_ = 1;
  bool initialised_ = false;
};

// This process's share of one envelope: the probes p with p % size == rank.
struct ProbeShare {
  int rank = 0;
  int size = 1;
  bool owns(int p) const { return p % size == rank; }
};

namespace detail {

// Byte archives of the messages between ranks (same binary on every rank, so raw bytes of
// arithmetic values are portable between them). `a(x)` writes x (ByteWriter) or reads into
// x (ByteReader); aggregates provide `template <class A> void io(A&, T&)` found by ADL.
class ByteWriter {
 public:
  template <class T>
  requires std::is_arithmetic_v<T> || std::is_enum_v<T>
  void operator()(T& v) { raw(&v, sizeof v); }
  template <class T>
  requires std::is_arithmetic_v<T>
  void operator()(std::vector<T>& v) {
    std::uint64_t n = v.size();
    (*this)(n);
    raw(v.data(), n * sizeof(T));
  }
  template <class T>
  requires(!std::is_arithmetic_v<T>) void operator()(std::vector<T>& v) {
    std::uint64_t n = v.size();
    (*this)(n);
    for (T& x : v) (*this)(x);
  }
  void operator()(std::string& s) {
    std::uint64_t n = s.size();
    (*this)(n);
    raw(s.data(), n);
  }
  template <int R, int C, int O, int MR, int MC>
  void operator()(Eigen::Matrix<double, R, C, O, MR, MC>& m) {
    static_assert(R > 0 && C > 0, "fixed-size matrices only");
    raw(m.data(), sizeof(double) * R * C);
  }
  template <class T>
  void operator()(T& t) {
    io(*this, t);
  }
  std::vector<char>& bytes() { return bytes_; }

 private:
  void raw(const void* p, std::size_t n) {
    const char* c = static_cast<const char*>(p);
    bytes_.insert(bytes_.end(), c, c + n);
  }
  std::vector<char> bytes_;
};

class ByteReader {
 public:
  explicit ByteReader(const std::vector<char>& bytes) : bytes_(bytes) {}
  template <class T>
  requires std::is_arithmetic_v<T> || std::is_enum_v<T>
  void operator()(T& v) { raw(&v, sizeof v); }
  template <class T>
  requires std::is_arithmetic_v<T>
  void operator()(std::vector<T>& v) {
    std::uint64_t n = 0;
    (*this)(n);
    if (n > (bytes_.size() - at_) / sizeof(T)) overrun();
    v.resize(n);
    raw(v.data(), n * sizeof(T));
  }
  // Elements of another kind (strings, records): each takes at least one byte, which bounds n.
  template <class T>
  requires(!std::is_arithmetic_v<T>) void operator()(std::vector<T>& v) {
    std::uint64_t n = 0;
    (*this)(n);
    if (n > bytes_.size() - at_) overrun();
    v.resize(n);
    for (T& x : v) (*this)(x);
  }
  void operator()(std::string& s) {
    std::uint64_t n = 0;
    (*this)(n);
    if (n > bytes_.size() - at_) overrun();
    s.resize(n);
    raw(s.data(), n);
  }
  template <int R, int C, int O, int MR, int MC>
  void operator()(Eigen::Matrix<double, R, C, O, MR, MC>& m) {
    raw(m.data(), sizeof(double) * R * C);
  }
  template <class T>
  void operator()(T& t) {
    io(*this, t);
  }
  bool done() const { return at_ == bytes_.size(); }

 private:
  [[noreturn]] static void overrun() {
    throw std::runtime_error("MPI probe message shorter than expected");
  }
  void raw(void* p, std::size_t n) {
    if (n > bytes_.size() - at_) overrun();
    if (n > 0) std::memcpy(p, bytes_.data() + at_, n);
    at_ += n;
  }
  const std::vector<char>& bytes_;
  std::size_t at_ = 0;
};

// One envelope's probes across the ranks, as seen by the envelope function that computes
// them. On rank 0 of a K > 1 session the constructor sends the task to every worker; inside
// a worker's serve() it only reports the worker's share. exchange() then sends a worker's
// packed results to rank 0, or on rank 0 receives every worker's (in rank order). If rank 0
// leaves early (an exception), the destructor still receives the workers' replies, so the
// ranks stay in step for the next task.
// The processes an envelope's probes are shared over: the MPI session's ranks (1 without
// one). Callers that batch several envelopes into one pool of tasks need 1.
int probe_ranks();

class ProbeTaskScope {
 public:
  ProbeTaskScope(const std::string& method, const std::string& plane, const DemSystem& state,
                 double amplitude, const std::vector<double>& theta_deg,
                 const ProbeOptions& options);
  ~ProbeTaskScope();
  ProbeTaskScope(const ProbeTaskScope&) = delete;
  ProbeTaskScope& operator=(const ProbeTaskScope&) = delete;

  const ProbeShare& share() const { return share_; }
  bool is_worker() const { return share_.rank != 0; }
  // Worker: sends `mine` and returns {}. Rank 0: the K-1 workers' buffers; throws (after all
  // replies are in) the first error a worker reported.
  std::vector<std::vector<char>> exchange(std::vector<char> mine);

 private:
  ProbeShare share_;
  int next_reply_ = 0;  // rank 0: the next worker whose reply is due (0: none is)
};

}  // namespace detail
}  // namespace rendulic::dem

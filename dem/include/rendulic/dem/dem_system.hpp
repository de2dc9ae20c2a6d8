// The DEM engine: particles in a deforming orthorhombic periodic cell, integrated with
// velocity Verlet in peculiar-velocity form (docs/physics.md sections 1-3, seed paper section 2).
//
// Scheme (one step of length dt, imposed diagonal velocity gradient D, S = exp(D dt)):
//   1. v' <- v' + dt/2 * F(t)/m                       (half kick)
//   2. x  <- S (x + dt v')                            (peculiar drift, then exact affine map)
//      L  <- S L, E <- E + D dt                       (log strain: trace-free D keeps V exactly)
//   3. F(t+dt) = sum_contacts (k delta + gamma d(delta)/dt) n - gamma_b v'
//      with d(delta)/dt = -n . (v'_i - v'_j + D l): the true relative normal velocity,
//      including the affine part; the velocities of the dissipative terms are predicted
//      as v'(t) + dt F(t)/m (second order; plain half-step velocities would lag by dt/2
//      and shift the contact duration and restitution at first order)
//   4. v' <- v' + dt/2 * F(t+dt)/m                    (half kick)
// The inertial terms -D v' - D^2 x of the peculiar equation of motion are dropped (as in
// LAMMPS `fix deform remap x` and MercuryDPM's Lees-Edwards boxes); relative to the contact
// forces they are O(D t_c) ~ 1e-6 at the rates of this mission. The conservative part is the
// symplectic Verlet scheme; the dissipative part is explicit with a second-order predictor.
//
// Parallel (OpenMP) with results that do not depend on the number of threads: the rows of the
// half neighbour list are cut into a fixed number of blocks (block_count(N), team.hpp), each
// block accumulates the forces on its own rows in place and those on partners outside it into a
// compact buffer of its own, and each particle then adds the buffers that hold a contribution
// to it in block order. Every other reduction is per particle, serial or order-free (max). A
// step therefore gives bitwise the same result on 1, 2 or 17 threads, which lets the engine
// choose its team size while running (TeamController, team.hpp): on a loaded machine a team
// whose members are descheduled in turn is slower than one thread, and is dropped.
#pragma once

#include <Eigen/Dense>
#include <atomic>
#include <cstdint>
#include <mutex>
#include <new>
#include <string>
#include <vector>

#include "rendulic/dem/cell.hpp"
#include "rendulic/dem/contact.hpp"
#include "rendulic/dem/measures.hpp"
#include "rendulic/dem/neighbor_list.hpp"
#include "rendulic/dem/particles.hpp"
#include "rendulic/dem/team.hpp"

namespace rendulic::dem {

// 64-byte aligned doubles: packed 4-double records then never straddle a cache line.
template <class T>
struct CacheAlignedAllocator {
  using value_type = T;
  CacheAlignedAllocator() = default;
  template <class U>
  CacheAlignedAllocator(const CacheAlignedAllocator<U>&) {}
  T* allocate(std::size_t n) {
    return static_cast<T*>(::operator new (n * sizeof(T), std::align_val_t{64}));
  }
  void deallocate(T* p, std::size_t) { ::operator delete (p, std::align_val_t{64}); }
  bool operator==(const CacheAlignedAllocator&) const { return true; }
};
using AlignedVector = std::vector<double, CacheAlignedAllocator<double>>;

struct SystemOptions {
  Material material{};
  double dt_factor = 1.0 / 50.0;  // dt = dt_factor * t_c of the smallest pair
  double skin = 0.3;              // Verlet skin in units of <r>
  bool IsValid(std::string* why) const;
};

// Everything needed to continue a run bit-identically (same build, any thread count): the
// particle arrays, the cell, the clocks and the neighbour list's reference state (the list is
// a pure function of it, so a restored run rebuilds exactly the same list).
struct State {
  Particles particles;
  Eigen::Vector3d lengths = Eigen::Vector3d::Ones();
  Eigen::Vector3d strain_E = Eigen::Vector3d::Zero();  // accumulated log strain diag(E)
  Eigen::Vector3d last_D = Eigen::Vector3d::Zero();
  double time = 0;
  std::int64_t steps = 0;
  std::vector<double> ref_x, ref_y, ref_z;
  Eigen::Vector3d ref_lengths = Eigen::Vector3d::Ones();
  // Per-particle half skins of the list (neighbor_list.hpp); empty means skin / 2 for all.
  std::vector<double> ref_half_skin;
  // Frictional contacts: the tangential spring xi of each entry of the list (3 per entry, in
  // the list's order; empty without friction or when no contact has history) and the sliding
  // dissipation so far, J.
  std::vector<double> tangential_history;
  double sliding_dissipation = 0;
  // With rolling resistance, the rolling spring of each entry likewise (empty without).
  std::vector<double> rolling_history;
  // The stress diagonal (Pa) that the last step summed in its force loop, which the next
  // step(CellControl) reads, when that step summed it (a servo or step_measuring_stress step,
  // or a force refresh); unknown otherwise, and the next servo step measures it.
  Eigen::Vector3d last_stress_diag = Eigen::Vector3d::Zero();
  bool last_stress_known = false;
};

class DemSystem {
 public:
  // Throws InputError if the options are invalid (including dt beyond the stability limit)
  // or the particles do not fit the cell. Positions are wrapped into the cell.
  DemSystem(Particles particles, const PeriodicCell& cell, const SystemOptions& options);
  static DemSystem restore(const State& state, const SystemOptions& options);
  State save() const;

  // One step with the imposed velocity gradient diag(D) (1/s, positive = extension). A step
  // that would strain the cell by more than kMaxStrainPerStep (|D_aa| dt), or a D that is not
  // finite, throws InputError and changes nothing.
  static constexpr double kMaxStrainPerStep = 1e-2;
  // Empty when a strain rate `rate` (1/s, the largest |D_aa|) strains the cell by at most
  // kMaxStrainPerStep per step of `dt`; else the words of the refusal, "strains the cell by
  // 0.02 per time step (dt = ... s), more than 0.01", for the caller to name the rate.
  static std::string strain_per_step_excess(double rate, double dt);
  void step(const Eigen::Vector3d& D);
  void advance(std::int64_t n, const Eigen::Vector3d& D);
  // One step whose D comes from a cell control. Servo axes use the stress that the last step
  // summed (one step of lag); after a step that did not sum it (step(D)), the stress of now.
  void step(const CellControl& control);
  // One step with the imposed D that also sums the stress's diagonal (last_stress_diag()):
  // for a servo kept outside the engine, e.g. the integral servo of the paths (protocols.hpp).
  void step_measuring_stress(const Eigen::Vector3d& D);

  Measures measure() const;
  std::vector<Contact> contacts() const;
  Eigen::Matrix3d stress() const;  // eq. 1, Pa
  Eigen::Matrix3d fabric() const;  // eq. 2
  double kinetic_energy() const;   // translation of the peculiar velocities
  // Normal springs, plus the tangential ones with friction and the rolling ones with rolling.
  double elastic_energy() const;
  double rotational_energy() const;  // sum I omega^2 / 2 (zero without friction)
  // Dissipated by slip at the Coulomb limits: sliding, and rolling slip with rolling.
  double sliding_dissipation() const { return sliding_dissipation_; }
  double volume_fraction() const { return solid_volume_ / volume(); }

  // Positions and forces as of the last step (copied from the engine's records on demand):
  // after another step, call it again rather than keep the reference.
  const Particles& particles() const {
    sync_particles();
    return p_;
  }
  // E.g. to set gas velocities; forces stale. The next step or refresh takes its positions and
  // forces from here.
  Particles& mutable_particles() {
    sync_particles();
    particles_ahead_ = true;
    return p_;
  }
  const PeriodicCell& cell() const { return cell_; }
  // The cell's volume as the engine computes it: the product of its lengths, in the order of
  // operations that the stored runs were made with (cell().volume() is det h, which may differ
  // from it in the last bit).
  double volume() const { return cell_.lengths().prod(); }
  const SystemOptions& options() const { return options_; }
  const Material& material() const { return options_.material; }
  double dt() const { return dt_; }
  double time() const { return time_; }
  std::int64_t steps() const { return steps_; }
  // Accumulated log strain E (diagonal; extension positive). epsilon = -E.
  Eigen::Vector3d strain_E() const { return strain_E_; }
  Eigen::Vector3d last_D() const { return last_D_; }
  std::int64_t list_builds() const { return list_.builds(); }
  // Threads of the last step (1 when it ran serially).
  int team() const { return last_team_; }
  // 0 (the default): the team size is chosen while running, up to max_team(N,
  // omp_get_max_threads()); k > 0: always min(k, max_team(N, k)) threads (benchmarks).
  void set_fixed_team(int threads) { fixed_team_ = threads; }
  const TeamController& team_controller() const { return controller_; }
  // The frictionless pair loop's form (force_block): 0 (the default) chosen while running by
  // timing, 1 the branchy loop, 2 the compact one (tests, benchmarks). With friction: 0 and 1
  // each row's contacts first, 2 every row in the list's order. Results are the same.
  void set_fixed_loop(int form) { fixed_loop_ = form; }
  bool compact_loop() const { return compact_; }  // the form of the last step
  // Where a step's wall time goes, per thread of its team (rendulic bench --phases;
  // docs/performance.md "Where a team's step goes"): seconds summed over the steps since
  // set_phase_timing(true), which clears them. kick: the kick and drift of the thread's rows;
  // wait_kick: the barrier after it; forces: the pair loop over its blocks; wait_forces: the
  // barrier after that; finish: its rows' sums and closing half kick; list: the list builds
  // (thread 0, serial and team parts alike). A rebuild step's forces count too, outside a step's
  // region. Off (the default) a step reads no clock for it.
  struct Phases {
    double kick = 0, wait_kick = 0, forces = 0, wait_forces = 0, finish = 0, list = 0;
    std::int64_t steps = 0;  // steps whose kick this thread ran
  };
  void set_phase_timing(bool on);
  std::vector<Phases> phases() const;
  const TeamController& loop_controller() const { return loop_controller_; }
  // Diagonal of the stress from the last force evaluation that computed it (servo steps).
  Eigen::Vector3d last_stress_diag() const { return last_stress_diag_; }

  // Makes the current configuration the origin of strain_E() (e.g. at the start of a path).
  void reset_strain() { strain_E_.setZero(); }
  // Sets every peculiar velocity to zero (a relaxed snapshot for probing starts at rest).
  void zero_velocities();
  // Recomputes forces at the current positions/velocities (after editing particles).
  void refresh_forces();

 private:
  DemSystem() = default;
  void rebuild_list();
  // Copies positions and radii into the packed array the force loop gathers from.
  void pack_positions();
  void pack_positions(std::size_t lo, std::size_t hi);  // rows [lo, hi), pos4_ already sized
  // A step keeps positions in pos4_ and forces in the force records only (p_'s are not
  // written: the step's footprint, docs/performance.md "The step's footprint"); this copies
  // them into p_ once after a step, for any reader. Under a lock: const readers may share a
  // system across threads. On a team (a rebuild), each thread copies the rows it kicks.
  void sync_particles(int team = 1) const;
  // The blocks [b0, b1) of thread t of a team of T: the team's one split of the work.
  std::pair<std::size_t, std::size_t> blocks_of(std::size_t t, std::size_t T) const;
  // The rows of thread t of a team of T: those of the blocks it computes and kicks (all rows
  // before the first blocks).
  std::pair<std::size_t, std::size_t> rows_of(std::size_t t, std::size_t T) const;
  // The team of the work done at a list build: the last step's, at most one thread per block.
  int blocks_team() const;
  // After mutable_particles(): p_'s positions and forces into the records.
  void pack_particles();
  void note_list_built();  // after every build: blocks, targets, packed positions
  void make_blocks();
  void reset_contacts_first();  // partner_first_ or entry_first_, and first_end_
  // r_i - r_j of list entry e of row i, with its periodic image (cell lengths L): the one
  // expression of contacts() and elastic_energy().
  Eigen::Vector3d branch(std::size_t i, std::int64_t e, const Eigen::Vector3d& L) const;
  // Whether the last force evaluation held contact (i, j) (branch l, normal nrm) with the
  // stored spring at the Coulomb limit (contacts(): the sliding flag).
  bool held_at_limit(std::size_t i, std::size_t j, const Eigen::Vector3d& l,
                     const Eigen::Vector3d& nrm, double overlap,
                     const Eigen::Vector3d& spring) const;
  // Team size of the next step; *adaptive: the controller chose it (the step is timed).
  int choose_team(bool* adaptive);
  // Forces at the current positions from the velocities in va8_; then, if half_kick != 0,
  // v += half_kick F / m (the closing half kick of a step). Marks the records ahead of p_.
  template <bool kStress>
  void compute_forces(double half_kick, int team);
  // Inside a parallel region of T threads (or serially with T = 1): thread t's share of it.
  template <bool kStress>
  void forces_of_thread(std::size_t t, std::size_t T, double half_kick);
  // kCompact: the touching entries gathered first (the loop's two forms, dem_system.cpp).
  // handed: the team's hand-offs are prepared for this team (its handed slots read slot_in_).
  template <bool kStress, bool kCompact>
  void force_block(std::size_t b, bool handed);
  // The same with friction (docs/physics.md section 1b): normal and tangential forces, torques,
  // the history of each entry advanced when advancing_.
  // kRolling: with rolling resistance (its springs in hist_r_), a template argument so that
  // the path without it is the same code as before rolling existed.
  template <bool kStress, bool kRolling>
  void force_block_friction(std::size_t b, bool handed);
  // Copies the rows' mid-step velocities and angular velocities into rot16_ and clears their
  // force and torque accumulators (friction: force_block_friction adds to them); with
  // opening_kick, first the rotations' opening half kick (half_kick = dt / 2).
  void pack_rotations(std::size_t lo, std::size_t hi, double half_kick, bool opening_kick);
  // Before a rebuild: the history of the pairs in contact, keyed by pair, to carry over.
  void carry_history(const std::vector<std::int64_t>& old_offset,
                     const std::vector<std::int32_t>& old_index, const std::vector<double>& old,
                     const std::vector<double>& old_rolling);
  void init_rotations();
  void sum_stress();  // last_stress_diag_ from the per-particle terms of the last evaluation
  template <bool kStress>
  void step_impl(const Eigen::Vector3d& D);

  Particles p_;
  PeriodicCell cell_;
  SystemOptions options_;
  NeighborList list_;
  double dt_ = 0;
  double time_ = 0;
  std::int64_t steps_ = 0;
  double solid_volume_ = 0;
  Eigen::Vector3d strain_E_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d last_D_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d last_stress_diag_ = Eigen::Vector3d::Zero();
  bool last_stress_known_ = false;      // last_stress_diag_ is that of the current forces
  std::vector<double> stress_scratch_;  // per-particle diagonal stress (servo steps)
  // p_'s positions and forces lag the records (a step or force evaluation since the last
  // sync_particles), and p_ was handed out for editing (records to refresh from it).
  struct Lag {
    mutable std::mutex lock;
    std::atomic<bool> ahead{false};
    Lag() = default;
    Lag(const Lag& o) : ahead(o.ahead.load()) {}
    Lag& operator=(const Lag& o) {
      ahead.store(o.ahead.load());
      return *this;
    }
  };
  mutable Lag records_ahead_;
  bool particles_ahead_ = false;
  // The force loop gathers partner j's data at random: packed, one partner costs two cache
  // lines (position + radius; velocity + force accumulator) instead of ten separate arrays.
  AlignedVector pos4_;  // x, y, z, radius per particle, then the foreign slots
  // Per particle, then per slot: the velocity of the dissipative forces (x, y, z, unused) and
  // the pair-force accumulator (x, y, z, unused).
  AlignedVector va8_;
  AlignedVector ref4_;  // the list's reference position and half skin per particle
  // Blocks of rows (block_lo_[b] .. block_lo_[b+1]) and their slots (slot_lo_[b] ..
  // slot_lo_[b+1], records N + s of pos4_ and va8_: copies of particle slot_particle_[s] seen
  // through image slot_code_[s]). partner_: the list's partner of each entry, or its slot if
  // the partner lies outside the entry's block or is seen through another image.
  std::vector<std::size_t> block_lo_, slot_lo_;
  std::vector<std::int32_t> slot_particle_, partner_;
  // Frictionless: each row of partner_ with its entries in contact first, then the others, each
  // part in the list's order (reset at every build, ordered by force_block when the row's
  // contacts change); first_end_[i]: the end of row i's first part.
  std::vector<std::int32_t> partner_first_;
  std::vector<std::int64_t> first_end_;
  // With friction the same parts, of list entries (their history is the entry's): a row whose
  // second part does not touch skips it after one test per entry (force_block_friction).
  std::vector<std::int32_t> entry_first_;
  std::vector<std::uint8_t> slot_code_;  // the periodic image of each slot (NeighborList code)
  // Hand-offs between the threads of a team of handoff_team_ (prepare_handoffs): a slot of one
  // thread's block whose particle another thread kicks is filled by that thread, right after
  // its kick, into slot_in_ (the position and velocity records, 8 doubles per slot; with
  // friction also rot16_'s, 24), and the share the block leaves there goes back through
  // slot_out_ (with friction 8 doubles per slot, force and torque; without, the force alone in
  // 4, two slots a line: half the lines to fetch from the other core), both written
  // with non-temporal stores. A core's stores into lines the other core has read wait for those
  // lines to come back, and on this project's VMs that wait grows with the cores' distance
  // (docs/performance.md "Hand-offs past the caches").
  int handoff_team_ = 0;
  std::int64_t handoff_builds_ = -1;
  std::vector<std::vector<std::int32_t>> fills_;    // per thread: the slots it fills (slot_in_)
  std::vector<std::vector<std::int32_t>> returns_;  // per thread: the slots it returns (slot_out_)
  std::vector<std::uint8_t> slot_handed_;           // per slot: 1 if handed over
  AlignedVector slot_in_, slot_out_;
  void prepare_handoffs(int team);
  // Whether a region of T threads hands off (prepared for a team of T: OpenMP may give fewer).
  bool hands_off(std::size_t T) const;
  void hand_in(std::size_t t);
  void hand_out(std::size_t t);
  // slot_out_'s doubles per slot: force and torque with friction, the force alone without.
  std::size_t share_stride() const { return friction_ ? 8 : 4; }
  // make_blocks' scratch: per block its slots' keys (27 j + code, ascending), per thread of
  // its team a partner's first slot.
  std::vector<std::vector<std::int64_t>> block_keys_;
  std::vector<std::int32_t> first_slot_of_;
  std::int64_t blocks_builds_ = -1;  // list build the blocks belong to
  // Per-thread partial results of a step (two largest excesses), padded to a cache line.
  struct alignas(64) Top {
    double e1 = -1e300, e2 = -1e300;
  };
  std::vector<Top> tops_;
  TeamBarrier barrier_;  // the step region's two barriers (team.hpp: no system call per release)
  // set_phase_timing: per thread of the team, padded to a cache line (each thread writes its
  // own while the others run).
  struct alignas(64) PhaseClock {
    Phases p;
  };
  bool phase_timing_ = false;
  std::vector<PhaseClock> phase_clocks_;
  // Before a region of `team` threads (a step's, or the forces' after a rebuild): a clock for
  // each member when the phases are timed.
  void clock_phases_of(int team);
  TeamController controller_;
  int fixed_team_ = 0;
  // The pair loop's form as a two-rung ladder: "size" 1 the branchy loop, 2 the compact one.
  TeamController loop_controller_;
  int fixed_loop_ = 0;
  bool compact_ = false;
  int last_team_ = 1;
  bool team_started_ = false;  // a step has run on a team (the first one is not timed)
  // Friction (material().mu > 0): force_block_friction runs instead of force_block (its own
  // compaction and four-lane tangential law, dem_system.cpp).
  bool friction_ = false;
  bool advancing_ = false;    // a step (history advanced, slip counted) or a refresh (not)
  std::vector<double> hist_;  // xi per list entry (3 doubles), as its row sees the pair
  // Rolling resistance (material().mu_r > 0): the rolling spring per list entry (3 doubles;
  // the same for either order of the pair).
  bool rolling_ = false;
  std::vector<double> hist_r_;
  // Per row, then per slot: mid-step velocity, mid-step and predicted angular velocity, the
  // torque accumulator (4 doubles each).
  AlignedVector rot16_;
  std::vector<double> inv_inertia_;        // 1 / (2/5 m r^2)
  std::vector<double> block_dissipation_;  // per block, in the last evaluation
  double sliding_dissipation_ = 0;
};

}  // namespace rendulic::dem

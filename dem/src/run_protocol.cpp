// The protocol of a run up to the isotropic state (run_protocol.hpp; docs/physics.md section 4).
#include "rendulic/dem/run_protocol.hpp"

#include <cmath>

namespace rendulic::dem {

PreparedPacking prepare_packing(const DemRunOptions& o, std::uint64_t seed, const TaskFn& task,
                                const ProgressFn& progress) {
  auto start = [&](const char* name) {
    if (task) task(name);
  };
  start("gas");
  SystemOptions prep = loading_system_options(o);
  prep.material.gamma_b = o.prepare_gamma_b;
  check_time_step(prep.material, prep.dt_factor, "preparation.gamma_b");
  DemSystem sys = make_gas(prep, o.gas, seed);
  if (o.mix_time > 0) {
    const std::int64_t n = step_count(std::ceil(o.mix_time / sys.dt()), "preparation.mix_time");
    for (std::int64_t k = 0; k < n; ++k) {
      sys.step(Eigen::Vector3d::Zero());
      if (progress && k % 256 == 0) progress(double(k) / n);
    }
  }
  start("compress to nu0");
  CompressSummary c = compress_isotropic(sys, o.prepare, {}, progress);
  start("relax at nu0");
  const RelaxSummary r = relax(sys, o.relax, progress);
  const Measures at_nu0 = sys.measure();
  const std::int64_t steps = sys.steps();
  // Every later step runs with the material's own background damping.
  return {DemSystem::restore(sys.save(), loading_system_options(o)), at_nu0, std::move(c), r,
          steps};
}

SystemOptions loading_system_options(const DemRunOptions& o) {
  SystemOptions s = o.system;
  // Rolling resistance with it: mu_r > 0 needs mu > 0, and a dense loading wants neither.
  s.material.mu *= o.loading_friction_factor;
  s.material.mu_r *= o.loading_friction_factor;
  return s;
}

void use_run_material(DemSystem& sys, const DemRunOptions& o) {
  if (o.loading_friction_factor == 1.0) return;
  sys = DemSystem::restore(sys.save(), o.system);
}

IsotropicLoading load_isotropic(DemSystem& sys, const CompressOptions& loading,
                                const RelaxOptions& relax_options, const SampleFn& sample,
                                const TaskFn& task, const ProgressFn& progress,
                                const PathOptions& servo_of) {
  IsotropicLoading out;
  const bool to_pressure = loading.target_pressure_star > 0;
  if (task) task(to_pressure ? "loading to P*" : "loading to nu_max");
  out.loading = compress_isotropic(sys, loading, sample, progress);
  if (to_pressure) {
    if (task) task("relax at P*");
    ServoOptions s = servo_of.servo(sys.material());
    s.max_rate = loading.rate_max;
    out.relax = relax_at_pressure(sys, loading.target_pressure_star * sys.material().k_star(),
                                  relax_options, s, progress);
  } else {
    if (task) task("relax at nu_max");
    out.relax = relax(sys, relax_options, progress);
  }
  return out;
}

}  // namespace rendulic::dem

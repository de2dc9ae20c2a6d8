// Model-generated calibration data for the tests: states on an axial-extension branch (stress
// and fabric as in the seed's Fig. 1: pressure ~2 GPa, fabric deviator growing negative), with
// envelopes computed by models/ model_envelope (an implementation independent of the
// calibration kernel) and optional Gaussian noise of a stated size.
#pragma once

#include <random>
#include <string>
#include <vector>

#include "rendulic/calibration/data.hpp"
#include "rendulic/core/conventions.hpp"
#include "rendulic/models/envelope.hpp"
#include "rendulic/models/law.hpp"
#include "rendulic/models/paths.hpp"

namespace rendulic::calibration::testing {

struct SyntheticState {
  std::string label;
  double p_ax, p_lat;  // Pa
  double f_ax, f_lat;  // fabric eigenvalues
};

inline std::vector<SyntheticState> extension_states() {
  return {{"s0", 2.0e9, 2.0e9, 1.8, 1.8},
          {"s1", 1.6e9, 2.0e9, 1.6, 1.9},
          {"s2", 1.3e9, 1.9e9, 1.4, 2.0},
          {"s3", 1.1e9, 1.7e9, 1.3, 2.0}};
}

// Noise: relative to the envelope's rms response, independently per component.
struct NoiseSpec {
  double relative = 0.0;
  unsigned seed = 7;
};

inline EnvelopeRecord envelope_of(const models::Law& law, const models::MaterialState& st,
                                  const std::string& name, double amplitude, int directions,
                                  models::EnvelopeMethod method, const NoiseSpec& noise,
                                  std::mt19937* rng) {
  models::EnvelopeOptions eo;
  eo.amplitude = amplitude;
  eo.directions = directions;
  eo.method = method;
  eo.step.tolerance = 1e-12;
  const EnvelopeRecord me = models::model_envelope(law, st, eo);
  EnvelopeRecord e = probe_set(name, amplitude, directions);
  double s2 = 0.0, f2 = 0.0;
  for (int i = 0; i < directions; ++i) {
    e.stress.push_back(me.stress[i]);
    e.fabric.push_back(me.fabric[i]);
    s2 += e.stress.back().squaredNorm();
    f2 += e.fabric.back().squaredNorm();
  }
  if (noise.relative > 0.0) {
    std::normal_distribution<double> g(0.0, 1.0);
    const double ss = noise.relative * std::sqrt(s2 / directions);
    const double sf = noise.relative * std::sqrt(f2 / directions);
    for (int i = 0; i < directions; ++i) {
      e.stress[i] += ss * Eigen::Vector2d(g(*rng), g(*rng));
      e.fabric[i] += sf * Eigen::Vector2d(g(*rng), g(*rng));
    }
  }
  return e;
}

struct SyntheticSpec {
  std::vector<SyntheticState> states = extension_states();
  int directions = 36;
  double elastic_amplitude = 5e-5;
  double plastic_amplitude = 0.0;  // > 0: add an integrated elasto-plastic envelope
  double path_end = 0.0;           // != 0: add the undrained path to this eps_dev
  int path_samples = 30;
  NoiseSpec noise;
};

inline CalibrationData synthetic_data(const models::Law& law, const SyntheticSpec& spec) {
  CalibrationData d;
  d.source = "synthetic";
  std::mt19937 rng(spec.noise.seed);
  for (const auto& s : spec.states) {
    StateData st;
    st.label = s.label;
    st.stress = Eigen::Vector3d(s.p_ax, s.p_lat, s.p_lat).asDiagonal();
    st.fabric = Eigen::Vector3d(s.f_ax, s.f_lat, s.f_lat).asDiagonal();
    st.volume_fraction = 0.8;
    const models::MaterialState ms = law.make_state(st.stress, st.fabric, st.volume_fraction);
    st.envelopes.push_back(envelope_of(law, ms, "elastic", spec.elastic_amplitude, spec.directions,
                                       models::EnvelopeMethod::kRate, spec.noise, &rng));
    if (spec.plastic_amplitude > 0.0)
      st.envelopes.push_back(envelope_of(law, ms, "plastic", spec.plastic_amplitude,
                                         spec.directions, models::EnvelopeMethod::kIntegrated,
                                         spec.noise, &rng));
    d.states.push_back(std::move(st));
  }
  if (spec.path_end != 0.0) {
    const auto& s0 = spec.states.front();
    const models::MaterialState ms =
        law.make_state(Eigen::Vector3d(s0.p_ax, s0.p_lat, s0.p_lat).asDiagonal(),
                       Eigen::Vector3d(s0.f_ax, s0.f_lat, s0.f_lat).asDiagonal(), 0.8);
    models::PathOptions po;
    po.steps = spec.path_samples;
    po.step.tolerance = 1e-12;
    const models::PathSeries ps = models::undrained_axisymmetric_path(law, ms, spec.path_end, po);
    if (!ps.success) throw std::runtime_error("synthetic path: " + ps.reason);
    d.path.eps_dev = ps.eps_dev;
    d.path.stress = ps.stress;
    d.path.fabric = ps.fabric;
    d.path.volume_fraction = 0.8;
  }
  return d;
}

// The elasto-plastic law's parameters behind the synthetic data of several tests: an
// anisotropic elastic part, yield near 2e-3, and a steady state reached within the path.
inline const std::vector<std::pair<std::string, double>> kElastoplasticTruth = {
    {"B", 2.2e10}, {"G", 3e9},     {"beta_A", 0.8},  {"c_F", 4.0},     {"p_ref", 2e9},
    {"m_e", 2e-3}, {"M_ss", 0.45}, {"beta_s", 40.0}, {"beta_F", 25.0}, {"F_dev_max", 0.6}};

inline std::unique_ptr<models::Law> law_with(const std::string& name,
                                             const std::vector<std::pair<std::string, double>>& p) {
  auto law = models::make_law(name);
  std::string why;
  for (const auto& [k, v] : p)
    if (!law->set_parameter(k, v, &why)) throw std::runtime_error(why);
  return law;
}

}  // namespace rendulic::calibration::testing

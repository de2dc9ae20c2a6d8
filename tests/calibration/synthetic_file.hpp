// Synthetic calibration data written as a results file (docs/results.md), the layout another DEM
// code would convert to: /material k_star and k, every state's stress, fabric, volume fraction
// and eps_dev, and its envelopes with directions, strain and starred stress pairs, fabric pairs
// and the tensors. Used by the end-to-end tests of `rendulic calibrate`.
#pragma once

#include <Eigen/Dense>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "rendulic/calibration/data.hpp"
#include "rendulic/core/conventions.hpp"
#include "rendulic/core/results.hpp"

namespace rendulic::calibration::testing {

// Writes `data` into an open writer (the caller may add more, then commits).
inline void write_results(ResultsWriter& w, const CalibrationData& data, double k_star) {
  w.attr("/material", "k_star", k_star);
  w.attr("/material", "k", 1e8);
  for (const auto& s : data.states) {
    const std::string g = "/states/" + s.label;
    w.write(g + "/stress", s.stress);
    w.write(g + "/fabric", s.fabric);
    w.attr(g, "volume_fraction", s.volume_fraction);
    w.attr(g, "eps_dev", -0.01);
    for (const auto& e : s.envelopes) {
      const std::string eg = g + "/envelopes/" + e.name;
      w.attr(eg, "amplitude", e.amplitude);
      w.attr(eg, "method", "linear_response");
      w.attr(eg, "directions", static_cast<std::int64_t>(e.size()));
      w.write(eg + "/theta_deg", e.theta_deg);
      w.write(eg + "/strain", e.strain);
      std::vector<Eigen::Vector2d> star;
      std::vector<Eigen::Matrix3d> ds, df;
      for (std::size_t i = 0; i < e.size(); ++i) {
        star.push_back(e.stress[i] / k_star);
        ds.push_back(from_rendulic_pair(e.stress[i]));
        df.push_back(from_rendulic_pair(e.fabric[i]));
      }
      w.write(eg + "/stress_star", star);
      w.write(eg + "/fabric", e.fabric);
      w.write(eg + "/d_stress", ds);
      w.write(eg + "/d_fabric", df);
    }
  }
}

}  // namespace rendulic::calibration::testing

// Synthetic results files for the app tests: envelopes from known linear maps (plus a shift
// for the plastic ones) and a Fig. 1-like path, so report verdicts and figures are known in
// advance. Header-only, shared by report_test.cpp and plot_system_test.cpp.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "rendulic/core/conventions.hpp"
#include "rendulic/core/results.hpp"

namespace rendulic::app::testing {
namespace fs = std::filesystem;

struct Envelope {
  std::vector<double> theta;
  std::vector<Eigen::Vector2d> strain, stress, fabric;
};

// Response = D u + shift for unit strain directions u, D given in the (iso, dev) frame, over
// the 36 probe directions of the project (from 35.26 deg: they hold 125.26 and 305.26).
inline Envelope make_envelope(const Eigen::Matrix2d& d_isodev, const Eigen::Vector2d& shift,
                              const Eigen::Matrix2d& f_isodev, const Eigen::Vector2d& f_shift,
                              double amplitude) {
  const Eigen::Matrix2d R = rendulic_to_iso_dev();
  const Eigen::Matrix2d D = R.transpose() * d_isodev * R, Df = R.transpose() * f_isodev * R;
  Envelope e;
  const Eigen::VectorXd theta = probe_directions_deg(36);
  for (Eigen::Index i = 0; i < theta.size(); ++i) {
    const double th = theta(i);
    const Eigen::Vector2d u(std::cos(deg_to_rad(th)), std::sin(deg_to_rad(th)));
    e.theta.push_back(th);
    e.strain.push_back(amplitude * u);
    e.stress.push_back(amplitude * D * u + shift);
    e.fabric.push_back(amplitude * Df * u + f_shift);
  }
  return e;
}

// The fabric split of an envelope: its fabric pairs as the kinematic part (the isotropic part
// as `volume`, the rest as `rotation`) plus a contact-set part of Frobenius norm `structural`
// per probe (along the deviator of x).
inline void write_split(ResultsWriter& w, const std::string& g, const Envelope& e,
                        double structural) {
  std::vector<Eigen::Matrix3d> vol, rot, con;
  const Eigen::Matrix3d dev =
      Eigen::Vector3d(2, -1, -1).asDiagonal().toDenseMatrix() / std::sqrt(6.0);
  for (const auto& f : e.fabric) {
    const Eigen::Matrix3d df = from_rendulic_pair(f);
    const Eigen::Matrix3d v = Eigen::Matrix3d::Identity() * df.trace() / 3.0;
    vol.push_back(v);
    rot.push_back(df - v);
    con.push_back(structural * dev);
  }
  w.write(g + "/d_fabric_volume", vol);
  w.write(g + "/d_fabric_rotation", rot);
  w.write(g + "/d_fabric_contacts", con);
}

// Exact ellipse (or line) attributes of an affine image of the unit circle.
inline void write_fit(ResultsWriter& w, const std::string& g, const Eigen::Matrix2d& map_isodev,
                      const Eigen::Vector2d& center, double amplitude) {
  const Eigen::Matrix2d R = rendulic_to_iso_dev();
  Eigen::JacobiSVD<Eigen::Matrix2d> svd(R.transpose() * map_isodev * R, Eigen::ComputeFullU);
  const Eigen::Vector2d s = svd.singularValues() * amplitude;
  double inc = rad_to_deg(std::atan2(svd.matrixU()(1, 0), svd.matrixU()(0, 0)));
  if (inc < 0) inc += 180;
  if (inc >= 180) inc -= 180;
  w.attr(g, "shape", s(1) < 1e-12 * s(0) ? "line" : "ellipse");
  w.attr(g, "center", std::vector<double>{center.x(), center.y()});
  w.attr(g, "semi_axes", std::vector<double>{s(0), s(1)});
  w.attr(g, "inclination_deg", inc);
  w.attr(g, "rms", 0.0);
}

inline Eigen::Matrix2d stiffness(double B, double G, double A) {
  Eigen::Matrix2d D;
  D << 3 * B, kSqrt3 * A, kSqrt3 * A, 2 * G;
  return D;
}

// A seed-like file: bulk constant, shear shrinking, anisotropy growing; plastic envelopes
// shifted and thinning to a line; fabric: isotropic-only elastic change, deviatoric plastic.
// plastic_method: the method attribute of the 2e-3 envelopes.
// yield: the yield strain of every state's elastic range (the plastic amplitude is 2e-3, so
// yield <= 1e-3 puts it beyond the elastic range); structural: the contact-set part of dF per
// elastic probe, in units of one contact flip of this file (nu 0.82, N 1000, w 3).
// xx_noise: a deterministic scatter of sigma*_xx along the path (C8's standard errors).
inline fs::path seed_like(const std::string& name, bool contradict_c1,
                          const std::string& plastic_method = "dynamic", double yield = 5e-4,
                          double structural = 0.0, double xx_noise = 0.0) {
  const fs::path dir = fs::path(RENDULIC_TEST_TMP) / "app_report" / name;
  fs::remove_all(dir);
  const double eps[] = {0.006, 0.021, 0.043, 0.068, 0.32};
  ResultsWriter w(dir / "results.h5");
  w.attr("/material", "n_particles", std::int64_t{1000});
  w.attr("/material", "w", 3.0);
  w.attr("/material", "r_mean", 1e-3);
  const double nu = 0.82;
  // One contact flip: 2 nu r_max^3 / (N <r^3>) with r in [0.5, 1.5] mm, <r^3> = 1.25 mm^3.
  const double flip = 2 * nu * 1.5 * 1.5 * 1.5 / (1000 * 1.25);
  for (int i = 0; i < 60; ++i) {  // Fig. 1 path: xx dips then recovers, lateral saturates
    const double x = 0.32 * i / 59.0;
    const double lat = 0.05 + 0.02 * (1 - std::exp(-x / 0.03));
    const double xx =
        0.05 - 0.03 * (1 - std::exp(-x / 0.02)) + 0.05 * x + xx_noise * std::sin(37.0 * i);
    w.append("/path/eps_dev", -x);
    w.append("/path/stress_star", Eigen::Matrix3d(Eigen::Vector3d(xx, lat, lat).asDiagonal()));
    const double fx = 0.9 - 0.2 * (1 - std::exp(-x / 0.03)),
                 fl = 0.9 + 0.1 * (1 - std::exp(-x / 0.03));
    w.append("/path/fabric", Eigen::Matrix3d(Eigen::Vector3d(fx, fl, fl).asDiagonal()));
  }
  for (int s = 0; s < 5; ++s) {
    const std::string g = "/states/s" + std::to_string(s + 1);
    w.attr(g, "eps_dev", -eps[s]);
    w.attr(g, "volume_fraction", nu);
    w.attr(g + "/elastic_range", "yield_strain", yield);
    w.attr(g + "/elastic_range", "yielded", std::int64_t{1});
    const double G = 1.0 / (1 + 10 * eps[s]), A = -0.4 * eps[s] / 0.32;
    const Eigen::Matrix2d De = stiffness(10.0, G, A);
    Eigen::Matrix2d Fe = Eigen::Matrix2d::Zero();
    Fe(0, 0) = 2.0;
    const Eigen::Vector2d c1shift =
        contradict_c1 ? Eigen::Vector2d(0, 3e-4) : Eigen::Vector2d(0, 0);
    Envelope el = make_envelope(De, c1shift, Fe, Eigen::Vector2d::Zero(), 5e-5);
    for (const char* method : {"dynamic", "linear_response"}) {
      const std::string e = g + "/envelopes/" + method + "_5e-05";
      w.attr(e, "method", method);
      w.attr(e, "amplitude", 5e-5);
      w.write(e + "/theta_deg", el.theta);
      w.write(e + "/strain", el.strain);
      w.write(e + "/stress_star", el.stress);
      w.write(e + "/fabric", el.fabric);
      write_split(w, e, el, std::string(method) == "dynamic" ? structural * flip : 0.0);
      write_fit(w, e + "/fit_stress", De, c1shift, 5e-5);
      write_fit(w, e + "/fit_fabric", Fe, Eigen::Vector2d::Zero(), 5e-5);
    }

    const double Gp = s == 4 ? 0.0 : 0.5 * G / (1 + s);
    const Eigen::Matrix2d Dp = stiffness(10.0, Gp, s == 4 ? 0.0 : A);
    Eigen::Matrix2d Fp;
    Fp << 2.0, 0.0, 0.0, 0.8;              // plastic: finite deviatoric fabric change
    if (s == 4) Fp << 2.0, 0.0, 0.0, 0.0;  // steady state: fabric line along 35.26 deg
    const Eigen::Vector2d shift = rendulic_from_iso_dev(Eigen::Vector2d(0, -2e-3 * (1 + s)));
    Envelope pl = make_envelope(Dp, shift, Fp, Eigen::Vector2d(1e-4, 0), 2e-3);
    if (s == 4) {  // keep a finite deviatoric spread to pass "finite change" on the last state
      for (auto& f : pl.fabric) f += rendulic_from_iso_dev(Eigen::Vector2d(0, 1e-5 * f.norm()));
    }
    const std::string p = g + "/envelopes/" + plastic_method + "_0.002";
    w.attr(p, "method", plastic_method);
    w.attr(p, "amplitude", 2e-3);
    w.write(p + "/theta_deg", pl.theta);
    w.write(p + "/strain", pl.strain);
    w.write(p + "/stress_star", pl.stress);
    w.write(p + "/fabric", pl.fabric);
    write_split(w, p, pl, 30 * flip);  // plastic: tens of contacts change per probe
    write_fit(w, p + "/fit_stress", Dp, shift, 2e-3);
    write_fit(w, p + "/fit_fabric", Fp, Eigen::Vector2d(1e-4, 0), 2e-3);
  }
  w.commit();
  return dir / "results.h5";
}

}  // namespace rendulic::app::testing

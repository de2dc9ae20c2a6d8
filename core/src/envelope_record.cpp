// The envelope record: appending a probe (envelope_record.hpp; docs/results.md).
#include "rendulic/core/envelope_record.hpp"

#include "rendulic/core/conventions.hpp"

namespace rendulic {

void EnvelopeRecord::add(double theta, const Eigen::Matrix3d& d_eps, const Eigen::Matrix3d& d_sigma,
                         const Eigen::Matrix3d& d_f) {
  theta_deg.push_back(theta);
  strain.push_back(plane_pair(plane, d_eps));
  stress.push_back(plane_pair(plane, d_sigma));
  stress_star.push_back(stress.back() / k_star);
  fabric.push_back(plane_pair(plane, d_f));
  d_stress.push_back(d_sigma);
  d_fabric.push_back(d_f);
}

void EnvelopeRecord::add(double theta, const Eigen::Matrix3d& d_eps, const Eigen::Matrix3d& d_sigma,
                         const Eigen::Matrix3d& d_f, const Eigen::Matrix3d& d_f_volume,
                         const Eigen::Matrix3d& d_f_rotation, const Eigen::Matrix3d& d_f_contacts) {
  add(theta, d_eps, d_sigma, d_f);
  d_fabric_volume.push_back(d_f_volume);
  d_fabric_rotation.push_back(d_f_rotation);
  d_fabric_contacts.push_back(d_f_contacts);
}

}  // namespace rendulic

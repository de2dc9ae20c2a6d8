// The envelope record: appending a probe, and the span of sizes an envelope may hold
// (envelope_record.hpp; docs/results.md, docs/fitting.md).
#include "rendulic/core/envelope_record.hpp"

#include <algorithm>
#include <cstddef>

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

std::optional<SpanExcess> span_excess(const std::vector<Eigen::Vector2d>& pairs) {
  if (pairs.size() < 3) return std::nullopt;
  std::vector<double> size(pairs.size());
  for (std::size_t i = 0; i < pairs.size(); ++i) size[i] = pairs[i].cwiseAbs().maxCoeff();
  const std::size_t k =
      static_cast<std::size_t>(std::max_element(size.begin(), size.end()) - size.begin());
  std::vector<double> sorted = size;
  const auto mid = sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() / 2);
  std::nth_element(sorted.begin(), mid, sorted.end());
  if (!(*mid > 0.0) || size[k] / kMaxEnvelopeSpan <= *mid) return std::nullopt;
  return SpanExcess{k, size[k], *mid};
}

}  // namespace rendulic

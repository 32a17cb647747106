#include "robot/rotation_bins.hpp"

#include <algorithm>
#include <cmath>

namespace qte::robot {

Eigen::Vector3d euler_xyz(const Eigen::Matrix3d& r) {
  const double b = std::asin(std::clamp(-r(2, 0), -1.0, 1.0));
  if (std::abs(r(2, 0)) > 1 - 1e-9) {  // gimbal lock: x and z turn about one axis; c = 0
    return Eigen::Vector3d(std::atan2(-r(1, 2), r(1, 1)), b, 0.0);
  }
  return Eigen::Vector3d(std::atan2(r(2, 1), r(2, 2)), b, std::atan2(r(1, 0), r(0, 0)));
}

Eigen::Matrix3d from_euler_xyz(const Eigen::Vector3d& a) {
  return (Eigen::AngleAxisd(a.z(), Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(a.y(), Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(a.x(), Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

Eigen::Vector3i rotation_bins(const Eigen::Matrix3d& rotation) {
  const Eigen::Vector3d degrees = euler_xyz(rotation) * 180.0 / M_PI;
  Eigen::Vector3i bins;
  for (int k = 0; k < 3; ++k) {
    const int bin = static_cast<int>(std::lround((degrees[k] + 180.0) / kRotationResolutionDeg));
    bins[k] = ((bin % kRotationBins) + kRotationBins) % kRotationBins;
  }
  return bins;
}

Eigen::Matrix3d rotation_from_bins(const Eigen::Vector3i& bins) {
  return from_euler_xyz((bins.cast<double>() * kRotationResolutionDeg - Eigen::Vector3d::Constant(180.0)) * M_PI / 180.0);
}

}  // namespace qte::robot

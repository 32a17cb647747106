// A pose as the records store it (an observation's gripper_pose, an action's pose, a
// transition's target_pose): float64 [7], x, y, z, qx, qy, qz, qw in the world frame.
#pragma once

#include <Eigen/Geometry>
#include <cmath>
#include <vector>

namespace qte::robot {

constexpr int kPoseValues = 7;

inline std::vector<double> pose_values(const Eigen::Vector3d& p, const Eigen::Quaterniond& q) {
  return {p.x(), p.y(), p.z(), q.x(), q.y(), q.z(), q.w()};
}
inline std::vector<double> pose_values(const Eigen::Isometry3d& pose) {
  return pose_values(pose.translation(), Eigen::Quaterniond(pose.linear()));
}

// The quaternion of 7 values, unnormalized (readers check it before use).
inline Eigen::Quaterniond quaternion_of(const double* values) {
  return Eigen::Quaterniond(values[6], values[3], values[4], values[5]);
}
// True when the 7 values are finite and the quaternion has unit length (within 1e-3): the
// poses readers accept.
inline bool pose_values_valid(const double* values) {
  for (int i = 0; i < kPoseValues; ++i)
    if (!std::isfinite(values[i])) return false;
  return std::abs(quaternion_of(values).norm() - 1.0) <= 1e-3;
}
// The pose of 7 values whose quaternion is finite and near unit length (normalized here).
inline Eigen::Isometry3d pose_from_values(const double* values) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() << values[0], values[1], values[2];
  pose.linear() = quaternion_of(values).normalized().toRotationMatrix();
  return pose;
}

}  // namespace qte::robot

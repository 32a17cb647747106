// A pose as the records store it (an observation's gripper_pose, an action's pose, a
// transition's target_pose): float64 [7], x, y, z, qx, qy, qz, qw in the world frame.
#pragma once

#include <Eigen/Geometry>
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
// The pose of 7 values whose quaternion is finite and near unit length (normalized here).
inline Eigen::Isometry3d pose_from_values(const double* values) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() << values[0], values[1], values[2];
  pose.linear() = quaternion_of(values).normalized().toRotationMatrix();
  return pose;
}

}  // namespace qte::robot

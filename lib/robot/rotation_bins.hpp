// The gripper's orientation as C2F-ARM encodes it in an action: three Euler angles, each in
// 72 bins of 5 degrees. One home for the encoding: keyframe turns demonstrated poses into
// bins, the networks' head has a Q value per bin, and the agent turns bins back into a pose.
#pragma once

#include <Eigen/Geometry>

namespace qte::robot {

// Euler angles 'xyz' (extrinsic x, then y, then z: R = Rz(c) Ry(b) Rx(a)), radians, a and c in
// [-pi, pi], b in [-pi/2, pi/2].
Eigen::Vector3d euler_xyz(const Eigen::Matrix3d& rotation);
Eigen::Matrix3d from_euler_xyz(const Eigen::Vector3d& angles);

// 72 bins of 5 degrees per axis: bin = round((deg + 180) / 5) mod 72; angle = bin * 5 - 180.
constexpr int kRotationBins = 72;
constexpr double kRotationResolutionDeg = 360.0 / kRotationBins;
Eigen::Vector3i rotation_bins(const Eigen::Matrix3d& rotation);
Eigen::Matrix3d rotation_from_bins(const Eigen::Vector3i& bins);

}  // namespace qte::robot

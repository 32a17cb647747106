// Keyframe discovery (ARM's published rule) and the rotation discretisation of C2F-ARM.
#pragma once

#include <Eigen/Geometry>
#include <array>
#include <vector>

namespace qte::keyframes {

struct FrameState {
  bool gripper_open = true;
  std::array<double, 7> joint_velocities{};
};

// Indices of the keyframes of one demonstration. Frame i > 0 is a keyframe when the gripper's
// open state differs from frame i-1's, when it is the last frame, or when the arm has stopped:
// every joint velocity within +-stopping_delta, frame i is not the second-to-last, the
// gripper state is the same at i-2, i-1, i and i+1, and no stop was taken in the 4 frames
// before. When the last two keyframes are adjacent, the first of them is dropped.
std::vector<int> discover_keyframes(const std::vector<FrameState>& frames, double stopping_delta = 0.1);

// Euler angles 'xyz' (extrinsic x, then y, then z: R = Rz(c) Ry(b) Rx(a)), radians, a and c in
// [-pi, pi], b in [-pi/2, pi/2].
Eigen::Vector3d euler_xyz(const Eigen::Matrix3d& rotation);
Eigen::Matrix3d from_euler_xyz(const Eigen::Vector3d& angles);

// 72 bins of 5 degrees per axis: bin = round((deg + 180) / 5) mod 72; angle = bin * 5 - 180.
constexpr int kRotationBins = 72;
constexpr double kRotationResolutionDeg = 360.0 / kRotationBins;
Eigen::Vector3i rotation_bins(const Eigen::Matrix3d& rotation);
Eigen::Matrix3d rotation_from_bins(const Eigen::Vector3i& bins);

}  // namespace qte::keyframes

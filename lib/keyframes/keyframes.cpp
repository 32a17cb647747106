#include "keyframes/keyframes.hpp"

#include <algorithm>
#include <cmath>

namespace qte::keyframes {

std::vector<int> discover_keyframes(const std::vector<FrameState>& frames, double stopping_delta) {
  const int n = static_cast<int>(frames.size());
  // (The published code compares with frames i-1 and i-2 also at i < 2, where Python's
  // negative indices wrap to the end of the demo; here those frames are never "stopped".)
  auto is_stopped = [&](int i, int stopped_buffer) {
    const bool next_is_second_to_last = i == n - 2;
    const bool gripper_unchanged = i < n - 2 && i >= 2 && frames[i].gripper_open == frames[i + 1].gripper_open &&
                                   frames[i].gripper_open == frames[i - 1].gripper_open &&
                                   frames[i - 2].gripper_open == frames[i - 1].gripper_open;
    bool small_velocity = true;
    for (double v : frames[i].joint_velocities) small_velocity &= std::abs(v) <= stopping_delta;
    return stopped_buffer <= 0 && small_velocity && !next_is_second_to_last && gripper_unchanged;
  };
  std::vector<int> keyframes;
  int stopped_buffer = 0;
  for (int i = 0; i < n; ++i) {
    const bool stopped = is_stopped(i, stopped_buffer);
    stopped_buffer = stopped ? 4 : stopped_buffer - 1;
    const bool last = i == n - 1;
    if (i > 0 && (frames[i].gripper_open != frames[i - 1].gripper_open || last || stopped)) keyframes.push_back(i);
  }
  if (keyframes.size() > 1 && keyframes[keyframes.size() - 1] - 1 == keyframes[keyframes.size() - 2])
    keyframes.erase(keyframes.end() - 2);
  return keyframes;
}

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

}  // namespace qte::keyframes

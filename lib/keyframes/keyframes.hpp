// Keyframe discovery (ARM's published rule).
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

}  // namespace qte::keyframes

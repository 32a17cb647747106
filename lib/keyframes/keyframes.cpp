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

}  // namespace qte::keyframes

// The proprioception every Q-attention network sees, tiled over its voxels: gripper open,
// the two finger positions (half the opening each, metres), and the episode time, scaled as
// C2F-ARM does: 1 at the first next-best pose, -1 at the last (of the record's
// episode_length; streams recorded before tasks had their own lengths: 10).
#pragma once

#include <vector>

#include "stream/record.hpp"
#include "tasks/episode.hpp"

namespace qte::qattention {

constexpr int kProprio = 4;

// From an 'obs' or 'frame' record (gripper_open, gripper_opening_m) and the number of
// next-best poses taken before it. Throws StreamError naming a missing field.
std::vector<float> proprio_of(const stream::Record& observation, int step);

}  // namespace qte::qattention

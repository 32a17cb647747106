// The 'action' record of a choice (formats/record-stream.md): the next-best gripper pose for
// plan-path and what chose it.
#pragma once

#include <cstdint>

#include "qattention/tree_expansion.hpp"
#include "stream/record.hpp"

namespace qte::qattention {

// pose (x, y, z, qx, qy, qz, qw: the last depth's voxel centre turned by the rotation bins),
// gripper_open, ignore_collisions; per depth the voxel's index, its grid's bounds, its centre
// and its Q-value (and at non-leaf depths the grid's best-ranked voxel); rotation_bins, value,
// k, explored, checkpoint_step and the episode's step.
stream::Record action_record(const Choice& choice, bool ignore_collisions, int k, bool explored,
                             int64_t checkpoint_step, int32_t step);

}  // namespace qte::qattention

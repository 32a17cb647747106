// Replayed transitions in the form the networks take: each sampled transition's grids along
// its action's path, its proprioception, the action's indices, and what its bootstrap target
// needs (the n-step reward, the discount, the observation reached).
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "learner/settings.hpp"
#include "replay/replay_buffer.hpp"
#include "stream/record.hpp"
#include "voxels/observation_cloud.hpp"

namespace qte::learner {

struct Minibatch {
  int size = 0;
  std::vector<std::vector<float>> grids;    // per depth: [B, V, V, V, C] over the action's bounds
  std::vector<float> proprio;               // [B, P]
  std::vector<std::vector<int64_t>> voxel;  // per depth: the action's voxel, flat (x, y, z order)
  std::vector<int64_t> rotation_bins;       // [B, 3]
  std::vector<int64_t> gripper;             // [B]: 1 = open (the gripper head's index)
  std::vector<float> demo;                  // [B]: 1 for a demonstration's transition, else 0
  std::vector<float> reward;                // as stored (100 on success); the discounted sum over n steps
  std::vector<float> discount;              // gamma^n, or 0 when the chain ends within n steps
  std::vector<std::shared_ptr<const voxels::ObservationCloud>> next_clouds;  // the replay's kept clouds
  std::vector<std::vector<float>> next_proprio;
  // Which samples reach the same next state (the same stored frame at the same step): equal
  // ids, so their bootstrap values are computed once. Empty: every sample its own state.
  std::vector<int64_t> next_state;
  std::vector<double> weights;              // importance weights
  std::vector<std::size_t> indices;         // replay indices
  double clouds_s = 0;  // wall time spent getting the point clouds (the benchmarks' table)
};

// Voxelizes the sampled transitions' frames. The transitions must have passed
// check_transition when they were read (it is not repeated for every sample).
Minibatch assemble_minibatch(const replay::ReplayBuffer& replay, const replay::Sample& sample,
                             const LearnerConfig& config);

// Checks one transition against the learner's settings (voxel count, depth count, index and
// bin ranges, a finite reward): call it on every transition as it is read, so a wrong input is
// refused with its position before it can reach a minibatch.
void check_transition(const stream::Record& transition, const LearnerConfig& config);

}  // namespace qte::learner

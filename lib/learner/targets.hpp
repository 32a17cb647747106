// The bootstrap targets of a minibatch, per depth: r * scale + discount * Q'(s', a'), clamped
// at 0 as published. a' and Q' come from two sets of networks, as in double DQN: the online
// networks choose (the voxel at every depth, the rotation bins, the gripper action), the
// target networks value what they chose.
//   tree_target_k = 0: a' is the greedy coarse-to-fine path; each depth's Q' is the target
//     network's Q of that depth's voxel (C2F-ARM).
//   tree_target_k = K: a' is the best path of tree expansion (qattention/tree_expansion.hpp)
//     with the online networks ranking the top-K voxels of every non-leaf grid and the target
//     networks valuing them; depth d's Q' is the path's value at d, (q_d + Q'_{d+1}) / 2, the
//     leaf's the target network's Q of its voxel (C2F-ARM+QTE, Algorithm 2).
// Each next state is evaluated once: a sample whose chain ended (discount 0) needs none, and
// samples reaching the same state (Minibatch::next_state) share its value.
#pragma once

#include <vector>

#include "learner/minibatch.hpp"
#include "qattention/tree_expansion.hpp"

namespace qte::learner {

// Per depth, per sample: the clamped bootstrap target of the translation Q; at the last
// depth also of the three rotation axes and the gripper.
struct Targets {
  std::vector<std::vector<float>> translation;  // [depth][B]
  std::vector<float> rotation;                  // [B, 3]
  std::vector<float> gripper;                   // [B]
  std::vector<double> mean_branches;            // per non-leaf depth: the trees' mean over the samples that
                                                // bootstrap (none without a tree)
};

// How many next states bootstrap_targets evaluates for `batch` (for benchmarks and metrics).
int next_states_evaluated(const Minibatch& batch);

Targets bootstrap_targets(const qattention::DepthEvaluator& online, const qattention::DepthEvaluator& target,
                          const LearnerConfig& config, const Minibatch& batch);

}  // namespace qte::learner

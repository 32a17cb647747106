// The learner's settings: every hyper-parameter of C2F-ARM's Q-attention learning, with the
// published value as default unless the table of settings in docs/learner.md says why not.
#pragma once

#include "qattention/tree_expansion.hpp"

#include <string>

#include "nets/qattention_net.hpp"
#include "voxels/voxel_grid.hpp"

namespace qte::learner {

struct LearnerConfig {
  nets::NetConfig net;  // architecture, base channels, voxels, channels, proprio (depth ignored)
  voxels::CoarseToFine hierarchy;
  int batch = 32;  // published 128: 4x the cost per step on a CPU (docs/learner.md, settings)
  double gamma = 0.99;
  double reward_scale = 0.01;
  double tau = 0.0025;
  double learning_rate = 5e-4;
  double weight_decay = 1e-6;
  double grad_clip_value = 0.01;  // each gradient element clipped to +-value, per depth (published); 0 = none
  double grad_clip_norm = 0;      // each depth's gradient L2 norm clipped to this; 0 = none
  double q_regularisation = 1.0;  // lambda of lambda * mean|Q| (translation; and the head's 218 outputs)
  double huber_delta = 1.0;
  int tree_target_k = 0;  // 0: double DQN down the greedy path; K >= 1: tree expansion (online ranks, target values)
  // With tree_target_k > 0, how the tree branches: fixed K = tree_target_k, or adaptive with
  // at most tree_target_k branches per node (qattention::Branching).
  qattention::Branching tree_branching;
  int n_step = 1;         // bootstrap after n transitions of a chain (the n-step return)
  // DQfD's large-margin loss on the demonstrations' transitions, max_a [Q(a) + m [a != a_E]] -
  // Q(a_E) per head (translation per depth; rotation axes and gripper), added to their TD loss:
  // the demonstrated action's Q pushed m above every other's. 0: none, as published (C2F-ARM
  // trains only the taken action's Q, so an output never demonstrated in a scene is never
  // told it is worse there: docs/learner.md).
  double demo_margin = 0;
  // Our variation: weight W of a cross-entropy term on the demonstrations' transitions, the
  // softmax of each of the last depth's head outputs (three rotation axes, the gripper) against
  // the demonstrated bin, the four's mean, added to their TD loss. It tells the head directly
  // which bin the demonstration took where the TD loss only raises that bin's Q. 0: none, as
  // published.
  double demo_cross_entropy = 0;
  // Our variation: a share F of each batch drawn from the demonstrations' transitions and the
  // rest from the agent's, each part prioritised within its kind (ReplayBuffer::sample), once
  // the replay holds both. It keeps what the demonstrations teach at a fixed weight through the
  // online phase, where the agent's transitions soon outnumber them. 0: one prioritised draw
  // over all transitions, as published.
  double demo_share = 0;

  // The settings a resumed run must share with its checkpoint, as JSON.
  std::string json() const;
  void validate() const;  // throws UsageError naming the first bad setting
  // Rough peak memory of one learner step, bytes: the networks' activations for the batch
  // (measured per sample at 16^3: light ~6 MB, arm ~80 MB; scaled by base channels and grid
  // size) and the tree target's grids of every branch.
  double step_memory_bytes() const;
  // Throws UsageError when a step would need more than `available_bytes` (the machine's memory).
  void check_memory(double available_bytes) const;
};

}  // namespace qte::learner

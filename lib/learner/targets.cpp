#include "learner/targets.hpp"

#include <algorithm>

namespace qte::learner {

Targets bootstrap_targets(const qattention::DepthEvaluator& online, const qattention::DepthEvaluator& target,
                          const LearnerConfig& config, const Minibatch& batch) {
  const int depths = config.hierarchy.depths, n = batch.size;
  std::vector<voxels::PointCloud> clouds;
  for (const auto& c : batch.next_clouds) clouds.push_back(c.view());
  // K = 1 follows the online networks' greedy path: double DQN down the coarse-to-fine depths.
  const qattention::Branching branching =
      config.tree_branching.adaptive() ? config.tree_branching : qattention::Branching(std::max(1, config.tree_target_k));
  const std::vector<qattention::Choice> choices =
      qattention::expand_batch(online, target, config.hierarchy, clouds, batch.next_proprio, branching);

  const float scale = static_cast<float>(config.reward_scale);
  const auto bootstrap = [&](int i, float next_value) {
    return std::max(0.0f, batch.reward[i] * scale + batch.discount[i] * next_value);  // clamped at 0, as published
  };
  Targets t;
  t.translation.assign(depths, std::vector<float>(n));
  for (int i = 0; i < n; ++i) {
    const qattention::Choice& c = choices[i];
    float value = c.q_values[depths - 1];
    for (int d = depths - 1; d >= 0; --d) {
      if (d < depths - 1) value = config.tree_target_k > 0 ? qattention::branch_value(c.q_values[d], value) : c.q_values[d];
      t.translation[d][i] = bootstrap(i, value);
    }
    for (int axis = 0; axis < 3; ++axis) t.rotation.push_back(bootstrap(i, c.rotation_q[axis]));
    t.gripper.push_back(bootstrap(i, c.gripper_q));
  }
  if (config.tree_target_k > 0) {
    t.mean_branches.assign(depths - 1, 0.0);
    for (const qattention::Choice& c : choices)
      for (int d = 0; d + 1 < depths; ++d) t.mean_branches[d] += static_cast<double>(c.branches[d]) / n;
  }
  return t;
}

}  // namespace qte::learner

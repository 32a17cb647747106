#include "learner/targets.hpp"

#include <algorithm>
#include <map>

namespace qte::learner {
namespace {

// The next states whose values the targets need, each once: samples with discount 0 (the chain
// ended) bootstrap nothing, and samples reaching the same state share it. Per sample, the index
// of its state among `clouds` (-1: none).
struct NextStates {
  std::vector<voxels::PointCloud> clouds;
  std::vector<std::vector<float>> proprios;
  std::vector<int> of_sample;
};

NextStates next_states(const Minibatch& batch) {
  NextStates states;
  std::map<int64_t, int> seen;  // next-state id -> index
  for (int i = 0; i < batch.size; ++i) {
    if (batch.discount[i] == 0) {
      states.of_sample.push_back(-1);
      continue;
    }
    const int64_t id = batch.next_state.empty() ? -1 - i : batch.next_state[i];
    const auto [at, added] = seen.emplace(id, static_cast<int>(states.clouds.size()));
    if (added) {
      states.clouds.push_back(batch.next_clouds[i]->view());
      states.proprios.push_back(batch.next_proprio[i]);
    }
    states.of_sample.push_back(at->second);
  }
  return states;
}

}  // namespace

int next_states_evaluated(const Minibatch& batch) { return static_cast<int>(next_states(batch).clouds.size()); }

Targets bootstrap_targets(const qattention::DepthEvaluator& online, const qattention::DepthEvaluator& target,
                          const LearnerConfig& config, const Minibatch& batch) {
  const int depths = config.hierarchy.depths, n = batch.size;
  const NextStates states = next_states(batch);
  // K = 1 follows the online networks' greedy path: double DQN down the coarse-to-fine depths.
  const qattention::Branching branching =
      config.tree_branching.adaptive() ? config.tree_branching : qattention::Branching(std::max(1, config.tree_target_k));
  const std::vector<qattention::Choice> choices =
      states.clouds.empty() ? std::vector<qattention::Choice>{}
                            : qattention::expand_batch(online, target, config.hierarchy, states.clouds, states.proprios,
                                                       branching);

  const float scale = static_cast<float>(config.reward_scale);
  const auto bootstrap = [&](int i, float next_value) {
    return std::max(0.0f, batch.reward[i] * scale + batch.discount[i] * next_value);  // clamped at 0, as published
  };
  qattention::Choice nothing;  // for discount 0: its values are multiplied by 0
  nothing.q_values.assign(depths, 0.0f);
  Targets t;
  t.translation.assign(depths, std::vector<float>(n));
  int bootstrapping = 0;
  if (config.tree_target_k > 0) t.mean_branches.assign(depths - 1, 0.0);
  for (int i = 0; i < n; ++i) {
    const int s = states.of_sample[i];
    const qattention::Choice& c = s < 0 ? nothing : choices[s];
    float value = c.q_values[depths - 1];
    for (int d = depths - 1; d >= 0; --d) {
      if (d < depths - 1) value = config.tree_target_k > 0 ? qattention::branch_value(c.q_values[d], value) : c.q_values[d];
      t.translation[d][i] = bootstrap(i, value);
    }
    for (int axis = 0; axis < 3; ++axis) t.rotation.push_back(bootstrap(i, c.rotation_q[axis]));
    t.gripper.push_back(bootstrap(i, c.gripper_q));
    if (s < 0 || config.tree_target_k == 0) continue;
    bootstrapping += 1;
    for (int d = 0; d + 1 < depths; ++d) t.mean_branches[d] += c.branches[d];
  }
  for (double& m : t.mean_branches) m = bootstrapping > 0 ? m / bootstrapping : 0.0;
  return t;
}

}  // namespace qte::learner

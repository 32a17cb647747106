// The learner of C2F-ARM (+QTE): one gradient step of every depth's Q-attention network on a
// minibatch of replayed transitions, as published: a 1-step bootstrap target per depth
// (double DQN: the online network's argmax valued by the target network; or, with
// tree_target_k, tree expansion over the target network's values), γ = 0.99, reward × 0.01,
// target clamped at 0, Huber loss on the taken voxel's Q (and at the last depth on the taken
// rotation bins' and gripper action's Q values), importance weights, λ·mean|Q|
// regularisation, Adam with weight decay, gradient clipping, and a soft target update.
//
// Free of LibTorch headers: the networks and the optimiser live behind a pointer.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "nets/qattention_net.hpp"
#include "replay/replay_buffer.hpp"
#include "stream/record.hpp"
#include "voxels/observation_cloud.hpp"
#include "voxels/voxel_grid.hpp"

namespace qte::learner {

struct LearnerConfig {
  nets::NetConfig net;  // architecture, base channels, voxels, channels, proprio (depth ignored)
  voxels::CoarseToFine hierarchy;
  int batch = 32;  // the published 128 costs 4x per step on a CPU for no gain in few-demo tasks
  double gamma = 0.99;
  double reward_scale = 0.01;
  double tau = 0.0025;
  double learning_rate = 5e-4;
  double weight_decay = 1e-6;
  double grad_clip = 5.0;          // max global gradient norm; 0 = none
  double q_regularisation = 1.0;   // λ of λ·mean|Q|
  double huber_delta = 1.0;
  int tree_target_k = 0;           // 0: double DQN; K >= 1: tree expansion over the target network
  int n_step = 1;                  // bootstrap after n transitions of a chain (the n-step return)

  // The settings a resumed run must share with its checkpoint, as JSON.
  std::string json() const;
  void validate() const;  // throws UsageError naming the first bad setting
};

// A sampled minibatch in the form the networks take.
struct Minibatch {
  int size = 0;
  std::vector<std::vector<float>> grids;    // per depth: [B, V, V, V, C] over the action's bounds
  std::vector<float> proprio;               // [B, P]
  std::vector<std::vector<int64_t>> voxel;  // per depth: the action's voxel, flat (x, y, z order)
  std::vector<int64_t> rotation_bins;       // [B, 3]
  std::vector<int64_t> gripper;             // [B]: 1 = open (the gripper head's index)
  std::vector<float> reward;                // as stored (100 on success); the discounted sum over n steps
  std::vector<float> discount;              // gamma^n, or 0 when the chain ends within n steps
  std::vector<voxels::ObservationCloud> next_clouds;
  std::vector<std::vector<float>> next_proprio;
  std::vector<double> weights;              // importance weights
  std::vector<std::size_t> indices;         // replay indices
};

// Voxelizes the sampled transitions' frames. The transitions must have passed
// check_transition when they were read (it is not repeated for every sample).
Minibatch assemble_minibatch(const replay::ReplayBuffer& replay, const replay::Sample& sample,
                             const LearnerConfig& config);

// Checks one transition against the learner's settings (voxel count, depth count, index and
// bin ranges, a finite reward): call it on every transition as it is read, so a wrong input is
// refused with its position before it can reach a minibatch.
void check_transition(const stream::Record& transition, const LearnerConfig& config);

struct StepStats {
  double loss = 0;
  std::vector<double> depth_loss, q_mean, q_max;  // per depth (translation Q of the batch)
  std::vector<double> td_errors;                  // per sample: mean over depths of |TD error|
};

// Per depth, per sample: the clamped bootstrap target of the translation Q; at the last
// depth also of the three rotation axes and the gripper.
struct Targets {
  std::vector<std::vector<float>> translation;  // [depth][B]
  std::vector<float> rotation;                  // [B, 3]
  std::vector<float> gripper;                   // [B]
};

class QLearner {
 public:
  // Online and target networks start equal; call nets::seed_torch first to reproduce them.
  explicit QLearner(LearnerConfig config);
  ~QLearner();

  const LearnerConfig& config() const { return config_; }
  int64_t step() const { return step_; }

  Targets targets(const Minibatch& batch) const;
  // One gradient step and soft target update. A non-finite loss throws Error before any
  // weight changes.
  StepStats train_step(const Minibatch& batch);

  std::vector<nets::QAttentionNet>& online();
  const std::vector<nets::QAttentionNet>& online() const;
  const std::vector<nets::QAttentionNet>& target() const;

  // The learner's checkpoint: the online networks with Adam's state (the record qte-select
  // reads), then the target networks, then `extra` (the tool's own state), in one atomic file.
  void save(const std::string& path, const stream::Record& extra) const;
  // Loads what save() wrote and returns `extra`; throws Error naming the first difference in
  // architecture, settings or tensors.
  stream::Record load(const std::string& path);

 private:
  struct Torch;
  LearnerConfig config_;
  std::unique_ptr<Torch> torch_;
  int64_t step_ = 0;
};

}  // namespace qte::learner

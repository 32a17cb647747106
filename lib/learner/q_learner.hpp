// The learner of C2F-ARM (+QTE): one gradient step of every depth's Q-attention network on a
// minibatch (learner/minibatch.hpp) towards its bootstrap targets (learner/targets.hpp), as
// published: Huber loss on the taken voxel's Q, at the last depth one mean over the five
// terms (translation, three rotation axes, gripper); lambda * mean|Q| regularisation of the
// translation volume and of the head's 218 outputs; both importance-weighted; Adam with weight
// decay; gradients clipped by value per depth; a soft target update after every step.
//
// Free of LibTorch headers: the networks and the optimiser live behind a pointer.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "learner/minibatch.hpp"
#include "learner/settings.hpp"
#include "learner/targets.hpp"
#include "nets/qattention_net.hpp"
#include "stream/record.hpp"

namespace qte::learner {

struct StepStats {
  double loss = 0;
  std::vector<double> depth_loss, q_mean, q_max;  // per depth (translation Q of the batch)
  std::vector<double> td_errors;                  // per sample: mean over depths of |TD error|
  std::vector<double> mean_branches;              // the tree target's, per non-leaf depth (Targets)
  // The last depth's head against the batch's own actions: per rotation axis and for the
  // gripper, the share of samples whose greedy bin is the transition's (on demonstrations: how
  // well the head fits them), and the mean Huber loss of the three rotation terms.
  std::vector<double> head_agreement;  // x, y, z, gripper
  double rotation_loss = 0;
  // Where the step's wall time went (the benchmarks' table): the bootstrap targets, the forwards
  // with gradients and the loss, the backward and clipping, Adam and the soft target update.
  double targets_s = 0, forward_s = 0, backward_s = 0, optimiser_s = 0;
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
  // The loss and the online networks' clipped gradients (left in their .grad()), without
  // changing any weight: train_step is this, Adam's step and the soft target update.
  StepStats gradients(const Minibatch& batch);

  std::vector<nets::QAttentionNet>& online();
  const std::vector<nets::QAttentionNet>& online() const;
  const std::vector<nets::QAttentionNet>& target() const;

  // The learner's checkpoint: the online networks with Adam's state and the hierarchy they
  // were trained on (the record qte-select reads), then the target networks, then `extra`
  // (the training loop's state), in one atomic file.
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

#include "learner/q_learner.hpp"

#include <chrono>
#include <cmath>

#include "common/error.hpp"
#include "nets/checkpoint.hpp"
#include "nets/qattention_modules.hpp"
#include "stream/field_names.hpp"
#include "stream/reader.hpp"
#include "stream/writer.hpp"
#include "voxels/grid_fields.hpp"

namespace qte::learner {
namespace {

torch::Tensor floats(std::vector<float> values, std::vector<int64_t> shape) {
  return torch::from_blob(values.data(), shape, torch::kFloat32).clone();
}
using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

torch::Tensor longs(const std::vector<int64_t>& values, std::vector<int64_t> shape) {
  return torch::from_blob(const_cast<int64_t*>(values.data()), shape, torch::kInt64).clone();
}

// DQfD's large margin of each row of q [n, A]: max_a [q(a) + m [a != taken]] - q(taken), >= 0,
// zero once the taken action (taken [n, 1]) leads every other by m.
torch::Tensor large_margin(const torch::Tensor& q, const torch::Tensor& taken, double m) {
  const auto margins = torch::full_like(q, m).scatter(1, taken, 0.0);
  return (q + margins).amax(1) - q.gather(1, taken).squeeze(1);
}

}  // namespace

struct QLearner::Torch {
  std::vector<nets::QAttentionNet> online, target;
  std::unique_ptr<torch::optim::Adam> adam;
};

QLearner::QLearner(LearnerConfig config) : config_(std::move(config)), torch_(std::make_unique<Torch>()) {
  config_.validate();
  config_.net.voxels = config_.hierarchy.voxels();
  torch_->online = nets::make_coarse_to_fine_nets(config_.net, config_.hierarchy.depths);
  torch_->target = nets::make_coarse_to_fine_nets(config_.net, config_.hierarchy.depths);
  torch::NoGradGuard no_grad;
  for (int d = 0; d < config_.hierarchy.depths; ++d) {
    auto from = torch_->online[d].module().parameters(), to = torch_->target[d].module().parameters();
    for (std::size_t i = 0; i < from.size(); ++i) to[i].copy_(from[i]);
  }
  torch_->adam = std::make_unique<torch::optim::Adam>(
      nets::parameters_of(torch_->online),
      torch::optim::AdamOptions(config_.learning_rate).weight_decay(config_.weight_decay));
}

QLearner::~QLearner() = default;

std::vector<nets::QAttentionNet>& QLearner::online() { return torch_->online; }
const std::vector<nets::QAttentionNet>& QLearner::online() const { return torch_->online; }
const std::vector<nets::QAttentionNet>& QLearner::target() const { return torch_->target; }

Targets QLearner::targets(const Minibatch& batch) const {
  return bootstrap_targets(qattention::network_evaluator(torch_->online), qattention::network_evaluator(torch_->target),
                           config_, batch);
}

StepStats QLearner::train_step(const Minibatch& batch) {
  StepStats stats = gradients(batch);
  const auto start = Clock::now();
  torch_->adam->step();
  {  // target <- tau * online + (1 - tau) * target
    torch::NoGradGuard no_grad;
    const double tau = config_.tau;
    for (int d = 0; d < config_.hierarchy.depths; ++d) {
      auto from = torch_->online[d].module().parameters(), to = torch_->target[d].module().parameters();
      for (std::size_t i = 0; i < from.size(); ++i) to[i].mul_(1 - tau).add_(from[i], tau);
    }
  }
  ++step_;
  stats.optimiser_s = seconds_since(start);
  return stats;
}

StepStats QLearner::gradients(const Minibatch& batch) {
  const voxels::CoarseToFine& h = config_.hierarchy;
  const int depths = h.depths, v = h.voxels(), n = batch.size, p = config_.net.proprio;
  auto start = Clock::now();
  const Targets targets = this->targets(batch);
  const double targets_s = seconds_since(start);
  start = Clock::now();
  const auto weights = torch::tensor(std::vector<float>(batch.weights.begin(), batch.weights.end()));
  const auto proprio = floats(batch.proprio, {n, p});
  const auto huber = [&](const torch::Tensor& q, const torch::Tensor& y) {
    return torch::nn::functional::huber_loss(
        q, y, torch::nn::functional::HuberLossFuncOptions().reduction(torch::kNone).delta(config_.huber_delta));
  };

  StepStats stats;
  std::vector<double> td(n, 0.0);
  torch::Tensor total = torch::zeros({});
  for (int d = 0; d < depths; ++d) {
    const auto grid = torch::from_blob(const_cast<float*>(batch.grids[d].data()), {n, v, v, v, config_.net.channels});
    const auto voxel = longs(batch.voxel[d], {n, 1});
    const nets::QOutputs out = torch_->online[d].module().forward(nets::channels_first(grid), proprio, voxel.view({n}));
    const auto q = out.translation.reshape({n, -1});
    const auto taken = q.gather(1, voxel).squeeze(1);
    const auto y = floats(targets.translation[d], {n});
    // Per sample: the TD loss (at the last depth one mean over translation, the three
    // rotation axes and the gripper) and lambda * mean|Q| (the translation volume; at the
    // last depth also the head's 3 x 72 + 2 outputs as one mean); both importance-weighted.
    // With --demo-margin, a demonstration's sample adds its large margins, meant as the TD loss.
    const double m = config_.demo_margin;
    auto per_sample = huber(taken, y);
    auto margin = m > 0 ? large_margin(q, voxel, m) : torch::Tensor();
    auto regulariser = q.abs().mean(1);
    if (d + 1 == depths) {
      const auto bins = longs(batch.rotation_bins, {n, 3, 1}), open = longs(batch.gripper, {n, 1});
      const auto rotation = out.rotation.gather(2, bins).squeeze(2);
      const auto gripper = out.gripper.gather(1, open).squeeze(1);
      per_sample = torch::cat({per_sample.unsqueeze(1), huber(rotation, floats(targets.rotation, {n, 3})),
                               huber(gripper, floats(targets.gripper, {n})).unsqueeze(1)}, 1).mean(1);
      if (m > 0)
        margin = torch::cat({margin.unsqueeze(1),
                             large_margin(out.rotation.reshape({n * 3, -1}), bins.view({n * 3, 1}), m).view({n, 3}),
                             large_margin(out.gripper, open, m).unsqueeze(1)}, 1).mean(1);
      regulariser = regulariser + torch::cat({out.rotation.reshape({n, -1}), out.gripper}, 1).abs().mean(1);
      if (config_.demo_cross_entropy > 0) {  // -log softmax at the demonstrated bins, the four heads' mean
        const auto log_p = torch::cat({out.rotation.log_softmax(2).gather(2, bins).squeeze(2),
                                       out.gripper.log_softmax(1).gather(1, open)}, 1);
        per_sample = per_sample - config_.demo_cross_entropy * log_p.mean(1) * floats(batch.demo, {n});
      }
      {
        torch::NoGradGuard no_grad;
        const auto rotation_agrees = out.rotation.argmax(2).eq(bins.squeeze(2)).to(torch::kDouble).mean(0);
        for (int axis = 0; axis < 3; ++axis) stats.head_agreement.push_back(rotation_agrees[axis].item<double>());
        stats.head_agreement.push_back(out.gripper.argmax(1).eq(open.squeeze(1)).to(torch::kDouble).mean().item<double>());
        stats.rotation_loss = huber(rotation, floats(targets.rotation, {n, 3})).mean().item<double>();
      }
    }
    if (m > 0) per_sample = per_sample + margin * floats(batch.demo, {n});
    const auto loss = ((per_sample + config_.q_regularisation * regulariser) * weights).mean();
    total = total + loss;
    const auto errors = (y - taken).abs().detach().contiguous();
    for (int i = 0; i < n; ++i) td[i] += errors[i].item<float>() / depths;
    stats.depth_loss.push_back(loss.item<double>());
    stats.q_mean.push_back(q.mean().item<double>());
    stats.q_max.push_back(q.max().item<double>());
  }
  stats.loss = total.item<double>();
  if (!std::isfinite(stats.loss)) throw Error("non-finite loss (" + std::to_string(stats.loss) + ")");
  stats.td_errors = td;
  stats.mean_branches = targets.mean_branches;
  stats.targets_s = targets_s;
  stats.forward_s = seconds_since(start);
  start = Clock::now();

  torch_->adam->zero_grad();
  total.backward();
  for (int d = 0; d < depths; ++d) {  // each depth's gradients alone (the depths are separate networks)
    const auto parameters = torch_->online[d].module().parameters();
    if (config_.grad_clip_norm > 0) torch::nn::utils::clip_grad_norm_(parameters, config_.grad_clip_norm);
    if (config_.grad_clip_value > 0) torch::nn::utils::clip_grad_value_(parameters, config_.grad_clip_value);
  }
  stats.backward_s = seconds_since(start);
  return stats;
}

void QLearner::save(const std::string& path, const stream::Record& extra) const {
  stream::Record online = nets::checkpoint_record(torch_->online, torch_->adam.get(), step_);
  online.set_string(fields::learner, config_.json());
  voxels::set_hierarchy(online, config_.hierarchy);
  stream::Record target = nets::checkpoint_record(torch_->target, nullptr, step_);
  target.set_string(fields::role, "target");
  stream::RecordWriter writer(path, {stream::WriteMode::replace});
  writer.write(online);
  writer.write(target);
  writer.write(extra);
  writer.close();
}

stream::Record QLearner::load(const std::string& path) {
  // Every record is read (and so checked); each is found by its role, not its place.
  stream::RecordReader reader(path);
  std::optional<stream::Record> online, target, extra;
  while (auto record = reader.next()) {
    std::optional<stream::Record>& slot = record->type() != record_type::checkpoint ? extra
                                          : record->has(fields::role) && record->string(fields::role) == "target"
                                              ? target
                                              : online;
    if (slot) throw StreamError(record->position, "a second '" + record->type() + "' record of this role: expected a learner checkpoint (online 'checkpoint', target 'checkpoint', the learner's state)");
    slot = std::move(record);
  }
  if (!online || !target || !extra)
    throw StreamError({path, reader.records_read(), reader.byte_offset()}, "expected a learner checkpoint (online 'checkpoint', target 'checkpoint', "
                                         "and the learner's state), the file ends early");
  if (!online->has(fields::learner) || !target->has(fields::role) || target->string(fields::role) != "target")
    throw StreamError(online->position, "not a learner checkpoint (no 'learner' settings and target networks): "
                                        "a checkpoint of networks only cannot be resumed");
  const std::string had = online->string(fields::learner), want = config_.json();
  if (had != want)
    throw Error(path + ": the checkpoint was trained with other settings: " + had + "; this run has " + want);
  step_ = nets::load_checkpoint_record(*online, torch_->online, torch_->adam.get());
  nets::load_checkpoint_record(*target, torch_->target, nullptr);
  return std::move(*extra);
}

}  // namespace qte::learner

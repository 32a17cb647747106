#include "learner/q_learner.hpp"

#include <cmath>
#include <sstream>

#include "common/error.hpp"
#include "nets/checkpoint.hpp"
#include "nets/qattention_modules.hpp"
#include "qattention/proprio.hpp"
#include "qattention/tree_expansion.hpp"
#include "stream/reader.hpp"
#include "stream/writer.hpp"

namespace qte::learner {
namespace {

Eigen::Vector3i unflatten(int64_t flat, int v) {
  return Eigen::Vector3i(static_cast<int>(flat / (v * v)), static_cast<int>((flat / v) % v), static_cast<int>(flat % v));
}

int64_t argmax(const float* q, int count) { return std::max_element(q, q + count) - q; }

std::string depth_field(int depth, const char* what) { return "depth" + std::to_string(depth) + "." + what; }

torch::Tensor floats(std::vector<float> values, std::vector<int64_t> shape) {
  return torch::from_blob(values.data(), shape, torch::kFloat32).clone();
}
torch::Tensor longs(const std::vector<int64_t>& values, std::vector<int64_t> shape) {
  return torch::from_blob(const_cast<int64_t*>(values.data()), shape, torch::kInt64).clone();
}

}  // namespace

std::string LearnerConfig::json() const {
  std::ostringstream s;
  s.precision(17);
  s << "{\"architecture\": \"" << nets::architecture_name(net.architecture) << "\", \"base_channels\": " << net.base_channels
    << ", \"voxels\": " << hierarchy.voxels() << ", \"depths\": " << hierarchy.depths
    << ", \"offset\": " << hierarchy.offset_m << ", \"bounds\": [" << hierarchy.scene.min_corner.x() << ", "
    << hierarchy.scene.min_corner.y() << ", " << hierarchy.scene.min_corner.z() << ", " << hierarchy.scene.size_m
    << "], \"batch\": " << batch << ", \"gamma\": " << gamma << ", \"reward_scale\": " << reward_scale
    << ", \"tau\": " << tau << ", \"learning_rate\": " << learning_rate << ", \"weight_decay\": " << weight_decay
    << ", \"grad_clip\": " << grad_clip << ", \"q_regularisation\": " << q_regularisation
    << ", \"huber_delta\": " << huber_delta << ", \"tree_target_k\": " << tree_target_k;
  if (n_step != 1) s << ", \"n_step\": " << n_step;  // absent for 1: checkpoints of 1-step runs stay valid
  s << "}";
  return s.str();
}

void LearnerConfig::validate() const {
  if (batch < 1) throw UsageError("--batch must be at least 1");
  if (!(gamma >= 0 && gamma <= 1)) throw UsageError("--gamma must be in [0, 1]");
  if (!(tau >= 0 && tau <= 1)) throw UsageError("--tau must be in [0, 1]");
  if (!(learning_rate > 0)) throw UsageError("--lr must be positive");
  if (!(weight_decay >= 0) || !(grad_clip >= 0) || !(q_regularisation >= 0) || !(huber_delta > 0) ||
      !(reward_scale > 0))
    throw UsageError("--weight-decay, --grad-clip and --q-reg must be >= 0; --huber-delta, --reward-scale > 0");
  if (tree_target_k < 0) throw UsageError("--tree-target must be >= 0");
  if (n_step < 1 || n_step > 10) throw UsageError("--n-step must be 1-10");
  if (hierarchy.depths < 1 || hierarchy.depths > 8) throw UsageError("--depths must be 1-8");
}

void check_transition(const stream::Record& t, const LearnerConfig& config) {
  const int v = config.hierarchy.voxels(), depths = config.hierarchy.depths;
  if (t.has("voxels") && t.scalar<int32_t>("voxels") != v)
    t.fail("voxels", std::to_string(v) + " voxels per side, as the networks (--voxels); the transition has " +
                         std::to_string(t.scalar<int32_t>("voxels")));
  for (int d = 0; d < depths; ++d) {
    if (!t.has(depth_field(d, "index")))
      t.fail(depth_field(d, "index"), "an action at each of the networks' " + std::to_string(depths) + " depths (--depths)");
    const auto index = t.array<int32_t>(depth_field(d, "index"));
    if (index.size() != 3) t.fail(depth_field(d, "index"), "int32 [3]");
    for (int axis = 0; axis < 3; ++axis)
      if (index[axis] < 0 || index[axis] >= v)
        t.fail(depth_field(d, "index"), "voxel indices in 0.." + std::to_string(v - 1) + " (--voxels " + std::to_string(v) + ")");
    if (t.array<double>(depth_field(d, "bounds")).size() != 4) t.fail(depth_field(d, "bounds"), "float64 [4]");
  }
  if (t.has(depth_field(depths, "index")))
    t.fail(depth_field(depths, "index"), "no more than the networks' " + std::to_string(depths) + " depths (--depths)");
  const auto bins = t.array<int32_t>("rotation_bins");
  if (bins.size() != 3) t.fail("rotation_bins", "int32 [3]");
  for (int axis = 0; axis < 3; ++axis)
    if (bins[axis] < 0 || bins[axis] >= nets::kRotationBins) t.fail("rotation_bins", "bins in 0..71");
  if (!std::isfinite(t.scalar<float>("reward"))) t.fail("reward", "a finite reward");
}

Minibatch assemble_minibatch(const replay::ReplayBuffer& replay, const replay::Sample& sample,
                             const LearnerConfig& config) {
  const voxels::CoarseToFine& h = config.hierarchy;
  const int v = h.voxels(), depths = h.depths;
  const std::size_t grid_floats = static_cast<std::size_t>(v) * v * v * voxels::kChannels;
  Minibatch b;
  b.size = static_cast<int>(sample.indices.size());
  b.indices = sample.indices;
  b.weights = sample.weights;
  b.grids.assign(depths, std::vector<float>(grid_floats * b.size));
  b.voxel.assign(depths, std::vector<int64_t>(b.size));
  for (int i = 0; i < b.size; ++i) {
    const std::size_t index = sample.indices[i];
    const stream::Record& t = replay.transition(index);  // checked when read (check_transition)
    const stream::Record& frame = replay.frame_of(index);
    const voxels::ObservationCloud cloud = voxels::observation_cloud(frame);
    std::vector<voxels::GridBounds> grids;
    for (int d = 0; d < depths; ++d) {
      const auto bounds = t.array<double>(depth_field(d, "bounds"));
      voxels::GridBounds g;
      g.min_corner = Eigen::Vector3d(bounds[0], bounds[1], bounds[2]);
      g.size_m = bounds[3];
      g.voxels = v;
      const auto index3 = t.array<int32_t>(depth_field(d, "index"));
      b.voxel[d][i] = (static_cast<int64_t>(index3[0]) * v + index3[1]) * v + index3[2];
      voxels::voxelize(cloud.view(), g, b.grids[d].data() + i * grid_floats);
    }
    const std::vector<float> p = qattention::proprio_of(frame, t.scalar<int32_t>("step"));
    b.proprio.insert(b.proprio.end(), p.begin(), p.end());
    const auto bins = t.array<int32_t>("rotation_bins");
    for (int axis = 0; axis < 3; ++axis) b.rotation_bins.push_back(bins[axis]);
    b.gripper.push_back(t.scalar<uint8_t>("gripper_open") != 0 ? 1 : 0);
    // The n-step return: rewards along the chain until it ends or n transitions are summed,
    // then the discounted value of the observation reached.
    std::size_t last = index;
    double reward = 0, discount = 1;
    for (int n = 0; n < config.n_step; ++n) {
      const stream::Record& u = replay.transition(last);
      reward += discount * u.scalar<float>("reward");
      discount *= config.gamma;
      if (u.scalar<uint8_t>("terminal") != 0) {
        discount = 0;
        break;
      }
      if (n + 1 == config.n_step) break;
      const std::optional<std::size_t> successor = replay.successor_of(last);
      if (!successor) break;
      last = *successor;
    }
    b.reward.push_back(static_cast<float>(reward));
    b.discount.push_back(static_cast<float>(discount));
    const stream::Record& next = replay.next_frame_of(last);
    b.next_clouds.push_back(voxels::observation_cloud(next));
    b.next_proprio.push_back(qattention::proprio_of(next, replay.transition(last).scalar<int32_t>("step") + 1));
  }
  return b;
}

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
  const voxels::CoarseToFine& h = config_.hierarchy;
  const int depths = h.depths, v = h.voxels(), cells = v * v * v, n = batch.size;
  const float scale = static_cast<float>(config_.reward_scale);
  // The next observation's value at every depth along the chosen path, and the heads' values.
  std::vector<std::vector<float>> value(depths, std::vector<float>(n));
  std::vector<float> rotation_value(3 * n), gripper_value(n);
  if (config_.tree_target_k > 0) {
    std::vector<voxels::PointCloud> clouds;
    for (const auto& c : batch.next_clouds) clouds.push_back(c.view());
    const auto choices = qattention::expand_batch(qattention::network_evaluator(torch_->target), h, clouds,
                                                  batch.next_proprio, config_.tree_target_k);
    for (int i = 0; i < n; ++i) {
      const auto& q = choices[i].q_values;
      value[depths - 1][i] = q[depths - 1];
      for (int d = depths - 2; d >= 0; --d) value[d][i] = (q[d] + value[d + 1][i]) / 2;  // Algorithm 2's value
      for (int axis = 0; axis < 3; ++axis) rotation_value[3 * i + axis] = choices[i].rotation_q[axis];
      gripper_value[i] = choices[i].gripper_q;
    }
  } else {
    // Double DQN down the coarse-to-fine path: the online network picks each depth's voxel
    // (and the next depth's grid around it), the target network values it.
    std::vector<voxels::GridBounds> bounds(n, h.scene);
    std::vector<float> proprio;
    for (const auto& p : batch.next_proprio) proprio.insert(proprio.end(), p.begin(), p.end());
    const std::size_t grid_floats = static_cast<std::size_t>(cells) * voxels::kChannels;
    std::vector<float> grids(grid_floats * n);
    for (int d = 0; d < depths; ++d) {
      for (int i = 0; i < n; ++i) voxels::voxelize(batch.next_clouds[i].view(), bounds[i], grids.data() + i * grid_floats);
      const nets::QValues online = torch_->online[d].predict(grids.data(), proprio.data(), n);
      const nets::QValues target = torch_->target[d].predict(grids.data(), proprio.data(), n);
      for (int i = 0; i < n; ++i) {
        const int64_t a = argmax(online.translation.data() + static_cast<std::size_t>(i) * cells, cells);
        value[d][i] = target.translation[static_cast<std::size_t>(i) * cells + a];
        if (d + 1 < depths) bounds[i] = h.bounds_at(d + 1, bounds[i].centre_of(unflatten(a, v)));
      }
      if (d + 1 == depths)
        for (int i = 0; i < n; ++i) {
          for (int axis = 0; axis < 3; ++axis) {
            const std::size_t at = (static_cast<std::size_t>(i) * 3 + axis) * nets::kRotationBins;
            rotation_value[3 * i + axis] = target.rotation[at + argmax(online.rotation.data() + at, nets::kRotationBins)];
          }
          const std::size_t at = static_cast<std::size_t>(i) * nets::kGripperActions;
          gripper_value[i] = target.gripper[at + argmax(online.gripper.data() + at, nets::kGripperActions)];
        }
    }
  }
  const auto bootstrap = [&](int i, float next_value) {
    return std::max(0.0f, batch.reward[i] * scale + batch.discount[i] * next_value);  // clamped at 0, as published
  };
  Targets t;
  t.translation.assign(depths, std::vector<float>(n));
  for (int d = 0; d < depths; ++d)
    for (int i = 0; i < n; ++i) t.translation[d][i] = bootstrap(i, value[d][i]);
  for (int i = 0; i < n; ++i) {
    for (int axis = 0; axis < 3; ++axis) t.rotation.push_back(bootstrap(i, rotation_value[3 * i + axis]));
    t.gripper.push_back(bootstrap(i, gripper_value[i]));
  }
  return t;
}

StepStats QLearner::train_step(const Minibatch& batch) {
  const voxels::CoarseToFine& h = config_.hierarchy;
  const int depths = h.depths, v = h.voxels(), n = batch.size, p = config_.net.proprio;
  const Targets targets = this->targets(batch);
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
    const nets::QOutputs out = torch_->online[d].module().forward(nets::channels_first(grid), proprio);
    const auto q = out.translation.reshape({n, -1});
    const auto taken = q.gather(1, longs(batch.voxel[d], {n, 1})).squeeze(1);
    const auto y = floats(targets.translation[d], {n});
    auto per_sample = huber(taken, y);
    auto regulariser = q.abs().mean();
    if (d + 1 == depths) {
      const auto rotation = out.rotation.gather(2, longs(batch.rotation_bins, {n, 3, 1})).squeeze(2);
      const auto gripper = out.gripper.gather(1, longs(batch.gripper, {n, 1})).squeeze(1);
      per_sample = per_sample + (huber(rotation, floats(targets.rotation, {n, 3})).sum(1) +
                                 huber(gripper, floats(targets.gripper, {n}))) / 4;
      regulariser = regulariser + out.rotation.abs().mean() + out.gripper.abs().mean();
    }
    const auto loss = (per_sample * weights).mean() + config_.q_regularisation * regulariser;
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

  torch_->adam->zero_grad();
  total.backward();
  if (config_.grad_clip > 0) torch::nn::utils::clip_grad_norm_(nets::parameters_of(torch_->online), config_.grad_clip);
  torch_->adam->step();
  {  // target <- tau * online + (1 - tau) * target
    torch::NoGradGuard no_grad;
    const double tau = config_.tau;
    for (int d = 0; d < depths; ++d) {
      auto from = torch_->online[d].module().parameters(), to = torch_->target[d].module().parameters();
      for (std::size_t i = 0; i < from.size(); ++i) to[i].mul_(1 - tau).add_(from[i], tau);
    }
  }
  ++step_;
  return stats;
}

void QLearner::save(const std::string& path, const stream::Record& extra) const {
  stream::Record online = nets::checkpoint_record(torch_->online, torch_->adam.get(), step_);
  online.set_string("learner", config_.json());
  stream::Record target = nets::checkpoint_record(torch_->target, nullptr, step_);
  target.set_string("role", "target");
  stream::RecordWriter writer(path, {stream::WriteMode::replace});
  writer.write(online);
  writer.write(target);
  writer.write(extra);
  writer.close();
}

stream::Record QLearner::load(const std::string& path) {
  stream::RecordReader reader(path);
  auto online = reader.next();
  auto target = reader.next();
  auto extra = reader.next();
  if (!online || !target || !extra)
    throw StreamError({path, reader.records_read(), reader.byte_offset()}, "expected a learner checkpoint (online 'checkpoint', target 'checkpoint', "
                                         "and the learner's state), the file ends early");
  if (!online->has("learner") || !target->has("role") || target->string("role") != "target")
    throw StreamError(online->position, "not a learner checkpoint (no 'learner' settings and target networks): "
                                        "a checkpoint of networks only cannot be resumed");
  const std::string had = online->string("learner"), want = config_.json();
  if (had != want)
    throw Error(path + ": the checkpoint was trained with other settings: " + had + "; this run has " + want);
  step_ = nets::load_checkpoint_record(*online, torch_->online, torch_->adam.get());
  nets::load_checkpoint_record(*target, torch_->target, nullptr);
  return std::move(*extra);
}

}  // namespace qte::learner

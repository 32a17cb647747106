// The learner: targets as published, learning a fixed replay, the soft target update, and a
// checkpoint that resumes a run step for step.
#include <gtest/gtest.h>

#include <filesystem>
#include <random>

#include "common/error.hpp"
#include "learner/q_learner.hpp"
#include "nets/qattention_modules.hpp"

using namespace qte;

namespace {

constexpr int V = 16;

// A frame with a synthetic point cloud: a floor of grey points and one coloured block whose
// position identifies the frame (what the networks can tell frames apart by).
stream::Record frame(int64_t episode, int32_t index, const Eigen::Vector3f& block, uint8_t red) {
  std::mt19937 rng(static_cast<uint32_t>(episode * 100 + index));
  std::uniform_real_distribution<float> u(0, 1);
  std::vector<float> xyz;
  std::vector<uint8_t> rgb;
  for (int i = 0; i < 1500; ++i) {
    xyz.insert(xyz.end(), {-0.3f + u(rng), -0.5f + u(rng), 0.76f});
    rgb.insert(rgb.end(), {90, 90, 90});
  }
  for (int i = 0; i < 300; ++i) {
    xyz.insert(xyz.end(), {block.x() + 0.04f * u(rng), block.y() + 0.04f * u(rng), block.z() + 0.04f * u(rng)});
    rgb.insert(rgb.end(), {red, 20, 20});
  }
  stream::Record r("frame");
  r.set_scalar<int64_t>("episode_key", episode);
  r.set_scalar<int32_t>("frame", index);
  const int64_t n = static_cast<int64_t>(rgb.size() / 3);
  r.set<float>("front.points", {1, n, 3}, xyz);
  r.set<uint8_t>("front.rgb", {1, n, 3}, rgb);
  r.set_scalar<uint8_t>("gripper_open", 1);
  r.set_scalar<double>("gripper_opening_m", 0.08);
  return r;
}

// A transition to the block's voxel at every depth, terminal with reward 100 (target 1).
stream::Record transition(const voxels::CoarseToFine& h, int64_t episode, const Eigen::Vector3d& goal, bool terminal) {
  stream::Record t("transition");
  t.set_scalar<int64_t>("episode_key", episode);
  t.set_scalar<int32_t>("frame", 0);
  t.set_scalar<int32_t>("next_frame", 1);
  t.set_scalar<int32_t>("step", 0);
  t.set_scalar<int32_t>("voxels", V);
  const auto indices = h.indices_of(goal);
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (int d = 0; d < h.depths; ++d) {
    const voxels::GridBounds b = h.bounds_at(d, centre);
    t.set<int32_t>("depth" + std::to_string(d) + ".index", {3}, indices[d].data());
    t.set<double>("depth" + std::to_string(d) + ".bounds", {4},
                  std::vector<double>{b.min_corner.x(), b.min_corner.y(), b.min_corner.z(), b.size_m});
    centre = b.centre_of(indices[d]);
  }
  t.set<int32_t>("rotation_bins", {3}, std::vector<int32_t>{36, 36, 18});
  t.set_scalar<uint8_t>("gripper_open", 0);
  t.set_scalar<uint8_t>("ignore_collisions", 0);
  t.set_scalar<float>("reward", terminal ? 100.0f : 0.0f);
  t.set_scalar<uint8_t>("terminal", terminal);
  t.set_scalar<uint8_t>("demo", 1);
  return t;
}

// Four episodes, each one terminal transition to its block.
replay::ReplayBuffer tiny_replay(const learner::LearnerConfig& config) {
  replay::ReplayBuffer replay;
  const Eigen::Vector3f blocks[4] = {{0.1f, -0.2f, 0.78f}, {0.3f, 0.2f, 0.78f}, {0.0f, 0.3f, 0.78f}, {0.4f, -0.3f, 0.78f}};
  for (int e = 0; e < 4; ++e) {
    replay.add(frame(e, 0, blocks[e], 220));
    replay.add(frame(e, 1, blocks[e], 220));
    replay.add(transition(config.hierarchy, e, blocks[e].cast<double>() + Eigen::Vector3d(0.02, 0.02, 0.02), true));
  }
  return replay;
}

learner::LearnerConfig small_config() {
  learner::LearnerConfig config;
  config.batch = 4;
  config.learning_rate = 1e-3;
  return config;
}

replay::Sample all_of(const replay::ReplayBuffer& replay) {
  replay::Sample s;
  for (std::size_t i = 0; i < replay.size(); ++i) s.indices.push_back(i);
  s.weights.assign(replay.size(), 1.0);
  return s;
}

std::vector<float> flat_parameters(const std::vector<nets::QAttentionNet>& nets) {
  std::vector<float> all;
  for (const auto& net : nets)
    for (const auto& p : net.module().parameters()) {
      const auto c = p.detach().contiguous();
      all.insert(all.end(), c.data_ptr<float>(), c.data_ptr<float>() + c.numel());
    }
  return all;
}

}  // namespace

TEST(QLearner, TerminalTargetsAreTheScaledRewardAndNonTerminalOnesBootstrap) {
  nets::set_torch_threads(2);
  nets::seed_torch(3);
  learner::LearnerConfig config = small_config();
  learner::QLearner learner(config);
  replay::ReplayBuffer replay = tiny_replay(config);
  learner::Minibatch batch = learner::assemble_minibatch(replay, all_of(replay), config);
  const learner::Targets terminal = learner.targets(batch);
  for (int d = 0; d < 2; ++d)
    for (float y : terminal.translation[d]) EXPECT_FLOAT_EQ(y, 1.0f);
  for (float y : terminal.gripper) EXPECT_FLOAT_EQ(y, 1.0f);

  // Not terminal, no reward: gamma times the target network's value of the online network's
  // greedy choice, clamped at 0.
  for (auto& d : batch.discount) d = 0.99f;
  for (auto& r : batch.reward) r = 0;
  const learner::Targets bootstrap = learner.targets(batch);
  const auto& target_nets = learner.target();
  std::vector<float> proprio;
  for (const auto& p : batch.next_proprio) proprio.insert(proprio.end(), p.begin(), p.end());
  std::vector<float> grid(static_cast<std::size_t>(V * V * V * voxels::kChannels) * batch.size);
  for (int i = 0; i < batch.size; ++i)
    voxels::voxelize(batch.next_clouds[i].view(), config.hierarchy.scene, grid.data() + i * V * V * V * voxels::kChannels);
  const nets::QValues online = learner.online()[0].predict(grid.data(), proprio.data(), batch.size);
  const nets::QValues target = target_nets[0].predict(grid.data(), proprio.data(), batch.size);
  for (int i = 0; i < batch.size; ++i) {
    const float* q = online.translation.data() + i * V * V * V;
    const int64_t a = std::max_element(q, q + V * V * V) - q;
    EXPECT_FLOAT_EQ(bootstrap.translation[0][i], std::max(0.0f, 0.99f * target.translation[i * V * V * V + a]));
  }
}

TEST(QLearner, OverfitsATinyFixedReplay) {
  nets::set_torch_threads(2);
  nets::seed_torch(5);
  learner::LearnerConfig config = small_config();
  config.q_regularisation = 0;  // the TD error alone
  learner::QLearner learner(config);
  replay::ReplayBuffer replay = tiny_replay(config);
  const learner::Minibatch batch = learner::assemble_minibatch(replay, all_of(replay), config);
  double first = 0, last = 0;
  for (int step = 0; step < 100; ++step) {
    const learner::StepStats stats = learner.train_step(batch);
    double td = 0;
    for (double e : stats.td_errors) td += e / stats.td_errors.size();
    if (step == 0) first = td;
    last = td;
  }
  EXPECT_GT(first, 0.3);
  EXPECT_LT(last, 0.05) << "mean |TD error| after 100 steps (first step: " << first << ")";
}

TEST(QLearner, TargetNetworkFollowsTau) {
  nets::set_torch_threads(2);
  nets::seed_torch(7);
  learner::LearnerConfig config = small_config();
  config.tau = 0.25;
  learner::QLearner learner(config);
  replay::ReplayBuffer replay = tiny_replay(config);
  const learner::Minibatch batch = learner::assemble_minibatch(replay, all_of(replay), config);
  const std::vector<float> target_before = flat_parameters(learner.target());
  EXPECT_EQ(target_before, flat_parameters(learner.online()));  // they start equal
  learner.train_step(batch);
  const std::vector<float> online = flat_parameters(learner.online()), target = flat_parameters(learner.target());
  ASSERT_EQ(online.size(), target.size());
  int moved = 0;
  for (std::size_t i = 0; i < online.size(); ++i) {
    EXPECT_NEAR(target[i], 0.25f * online[i] + 0.75f * target_before[i], 1e-6f + 1e-5f * std::abs(target[i]));
    moved += target[i] != target_before[i];
  }
  EXPECT_GT(moved, static_cast<int>(online.size() / 2));
}

TEST(QLearner, CheckpointResumesStepForStep) {
  nets::set_torch_threads(2);
  const auto dir = std::filesystem::temp_directory_path() / ("qte_learner_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  learner::LearnerConfig config = small_config();
  replay::ReplayBuffer replay = tiny_replay(config);
  const learner::Minibatch batch = learner::assemble_minibatch(replay, all_of(replay), config);

  nets::seed_torch(11);
  learner::QLearner straight(config);
  for (int i = 0; i < 6; ++i) straight.train_step(batch);

  nets::seed_torch(11);
  learner::QLearner first(config);
  for (int i = 0; i < 3; ++i) first.train_step(batch);
  stream::Record extra("learner");
  extra.set_scalar<int64_t>("transitions_read", 4);
  first.save((dir / "c.rec").string(), extra);

  nets::seed_torch(999);  // other initial weights: everything must come from the file
  learner::QLearner resumed(config);
  const stream::Record back = resumed.load((dir / "c.rec").string());
  EXPECT_EQ(back.scalar<int64_t>("transitions_read"), 4);
  EXPECT_EQ(resumed.step(), 3);
  EXPECT_EQ(flat_parameters(resumed.online()), flat_parameters(first.online()));
  EXPECT_EQ(flat_parameters(resumed.target()), flat_parameters(first.target()));
  for (int i = 0; i < 3; ++i) resumed.train_step(batch);
  EXPECT_EQ(flat_parameters(resumed.online()), flat_parameters(straight.online()));
  EXPECT_EQ(flat_parameters(resumed.target()), flat_parameters(straight.target()));

  // Other settings or another architecture: refused, naming the difference.
  learner::LearnerConfig other = config;
  other.net.architecture = nets::Architecture::arm;
  other.net.base_channels = 8;
  learner::QLearner wrong(other);
  try {
    wrong.load((dir / "c.rec").string());
    FAIL() << "loaded a checkpoint of another architecture";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("\"architecture\": \"light\""), std::string::npos) << e.what();
  }
  std::filesystem::remove_all(dir);
}

TEST(QLearner, RefusesTransitionsOfAnotherGrid) {
  learner::LearnerConfig config = small_config();
  voxels::CoarseToFine three = config.hierarchy;
  three.depths = 3;
  const stream::Record deeper = transition(three, 0, {0.1, 0.1, 0.8}, true);
  EXPECT_THROW(learner::check_transition(deeper, config), StreamError);
  stream::Record other = transition(config.hierarchy, 0, {0.1, 0.1, 0.8}, true);
  other.set_scalar<int32_t>("voxels", 32);
  try {
    learner::check_transition(other, config);
    FAIL();
  } catch (const StreamError& e) {
    EXPECT_NE(std::string(e.what()).find("16 voxels"), std::string::npos) << e.what();
  }
  EXPECT_NO_THROW(learner::check_transition(transition(config.hierarchy, 0, {0.1, 0.1, 0.8}, true), config));
}

TEST(QLearner, NonFiniteLossStopsBeforeAnyWeightChanges) {
  nets::set_torch_threads(2);
  nets::seed_torch(13);
  learner::LearnerConfig config = small_config();
  learner::QLearner learner(config);
  replay::ReplayBuffer replay = tiny_replay(config);
  learner::Minibatch batch = learner::assemble_minibatch(replay, all_of(replay), config);
  batch.weights[1] = std::nan("");  // (a NaN reward would be clamped away by the target's max with 0)
  const std::vector<float> before = flat_parameters(learner.online());
  EXPECT_THROW(learner.train_step(batch), Error);
  EXPECT_EQ(flat_parameters(learner.online()), before);
  EXPECT_EQ(learner.step(), 0);
}

TEST(QLearner, NStepReturnsFollowTheChain) {
  learner::LearnerConfig config = small_config();
  replay::ReplayBuffer replay;
  const Eigen::Vector3f block(0.1f, -0.2f, 0.78f);
  for (int32_t f = 0; f < 3; ++f) replay.add(frame(9, f, block, 220));
  stream::Record first = transition(config.hierarchy, 9, {0.1, -0.2, 0.8}, false);
  stream::Record second = transition(config.hierarchy, 9, {0.1, -0.2, 0.8}, true);
  second.set_scalar<int32_t>("frame", 1);
  second.set_scalar<int32_t>("next_frame", 2);
  second.set_scalar<int32_t>("step", 1);
  replay.add(first);
  replay.add(second);
  ASSERT_EQ(replay.successor_of(0), std::optional<std::size_t>(1));
  EXPECT_FALSE(replay.successor_of(1).has_value());

  const replay::Sample just_first{{0}, {1.0}};
  const learner::Minibatch one = learner::assemble_minibatch(replay, just_first, config);
  EXPECT_FLOAT_EQ(one.reward[0], 0);
  EXPECT_FLOAT_EQ(one.discount[0], 0.99f);
  config.n_step = 3;  // the chain ends after two: 0 + 0.99 * 100, nothing to bootstrap from
  const learner::Minibatch three = learner::assemble_minibatch(replay, just_first, config);
  EXPECT_FLOAT_EQ(three.reward[0], 99.0f);
  EXPECT_FLOAT_EQ(three.discount[0], 0);
  EXPECT_FLOAT_EQ(three.next_proprio[0][3], 1.0f - 2.0f * 2 / 9);  // the observation after step 1
}

// The learner: targets as published, learning a fixed replay, the soft target update, and a
// checkpoint that resumes a run step for step.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <random>

#include "common/error.hpp"
#include "learner/q_learner.hpp"
#include "learner_fixtures.hpp"
#include "nets/light_trunk.hpp"
#include "nets/qattention_modules.hpp"

using namespace qte;

namespace {

using namespace qte::test_support;

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
    voxels::voxelize(batch.next_clouds[i]->view(), config.hierarchy.scene, grid.data() + i * V * V * V * voxels::kChannels);
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

// A checkpoint holds fp32 parameters and Adam state whichever precision trained them: one
// trained with bf16 convolutions resumes in fp32 bit for bit and acts there, and back. Acting in
// bf16, the greedy voxel may differ from fp32's only where fp32 itself nearly ties: its fp32 Q
// is within bf16's rounding of the fp32 best.
TEST(QLearner, ACheckpointTrainedInBf16LoadsAndActsInFp32AndBack) {
  if (!nets::bf16_native_here()) GTEST_SKIP() << "no AVX-512 BF16 or AMX here";
  nets::set_torch_threads(2);
  const auto dir = std::filesystem::temp_directory_path() / ("qte_learner_bf16_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  learner::LearnerConfig config = small_config();
  replay::ReplayBuffer replay = tiny_replay(config);
  const learner::Minibatch batch = learner::assemble_minibatch(replay, all_of(replay), config);
  const stream::Record extra("learner");

  nets::use_precision(nets::Precision::bf16);
  nets::seed_torch(21);
  learner::QLearner bf16(config);
  for (int i = 0; i < 5; ++i) EXPECT_TRUE(std::isfinite(bf16.train_step(batch).loss));
  bf16.save((dir / "bf16.rec").string(), extra);

  nets::use_precision(nets::Precision::fp32);
  nets::seed_torch(998);
  learner::QLearner fp32(config);
  fp32.load((dir / "bf16.rec").string());
  EXPECT_EQ(flat_parameters(fp32.online()), flat_parameters(bf16.online()));
  EXPECT_EQ(flat_parameters(fp32.target()), flat_parameters(bf16.target()));

  // Acting: the depth-0 Q values of the batch's states in fp32 and in bf16.
  std::vector<float> grid(static_cast<std::size_t>(V * V * V * voxels::kChannels) * batch.size);
  for (int i = 0; i < batch.size; ++i)
    voxels::voxelize(batch.next_clouds[i]->view(), config.hierarchy.scene, grid.data() + i * V * V * V * voxels::kChannels);
  const nets::QValues in_fp32 = fp32.online()[0].predict(grid.data(), batch.proprio.data(), batch.size);
  nets::use_precision(nets::Precision::bf16);
  const nets::QValues in_bf16 = fp32.online()[0].predict(grid.data(), batch.proprio.data(), batch.size);
  nets::use_precision(nets::Precision::fp32);
  for (int i = 0; i < batch.size; ++i) {
    const float* q32 = in_fp32.translation.data() + i * V * V * V;
    const float* q16 = in_bf16.translation.data() + i * V * V * V;
    const float best = *std::max_element(q32, q32 + V * V * V);
    float scale = 1e-6f;
    for (int v = 0; v < V * V * V; ++v) {
      scale = std::max(scale, std::abs(q32[v]));
      EXPECT_NEAR(q16[v], q32[v], 0.04 * std::max(1e-3f, std::abs(best))) << "sample " << i << " voxel " << v;
    }
    const int64_t chosen = std::max_element(q16, q16 + V * V * V) - q16;
    EXPECT_GE(q32[chosen], best - 0.04f * scale) << "sample " << i << ": bf16's choice is no near-tie in fp32";
  }

  // And back: trained on in fp32, resumed in bf16 bit for bit.
  fp32.train_step(batch);
  fp32.save((dir / "fp32.rec").string(), extra);
  nets::use_precision(nets::Precision::bf16);
  learner::QLearner again(config);
  again.load((dir / "fp32.rec").string());
  EXPECT_EQ(flat_parameters(again.online()), flat_parameters(fp32.online()));
  EXPECT_TRUE(std::isfinite(again.train_step(batch).loss));
  nets::use_precision(nets::Precision::fp32);
  std::filesystem::remove_all(dir);
}

TEST(QLearner, RefusesTransitionsOfAnotherGrid) {
  learner::LearnerConfig config = small_config();
  voxels::CoarseToFine three = config.hierarchy;
  three.depths = 3;
  three.offsets_m = {0.15, 0.05};
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

// Demo augmentation starts chains at several frames, so one frame is acted on at different
// steps of different chains: the n-step return follows its own chain (the step after its
// own), not the newest transition acting on the frame reached.
TEST(QLearner, NStepReturnsStayInTheirChainWhereChainsShareAFrame) {
  learner::LearnerConfig config = small_config();
  replay::ReplayBuffer replay;
  const Eigen::Vector3f block(0.1f, -0.2f, 0.78f);
  for (int32_t f : {0, 5, 10, 20}) replay.add(frame(4, f, block, 220));
  const auto link = [&](int32_t from, int32_t to, int32_t step, bool terminal) {
    stream::Record t = transition(config.hierarchy, 4, {0.1, -0.2, 0.8}, terminal);
    t.set_scalar<int32_t>("frame", from);
    t.set_scalar<int32_t>("next_frame", to);
    t.set_scalar<int32_t>("step", step);
    t.set_scalar<float>("reward", terminal ? 100.0f : 0.0f);
    replay.add(t);
  };
  link(0, 10, 0, false);   // 0: chain from frame 0: keyframes 10, 20
  link(10, 20, 1, true);   // 1
  link(5, 10, 0, false);   // 2: chain from frame 5, same keyframes, same steps
  link(10, 20, 1, true);   // 3
  link(0, 5, 0, false);    // 4: a chain through frame 5 first: frame 10 at step 2
  link(5, 10, 1, false);   // 5
  link(10, 20, 2, true);   // 6: the newest transition acting on frame 10
  EXPECT_EQ(replay.successor_of(0), std::optional<std::size_t>(3));  // step 1 on frame 10 (1 and 3 are alike)
  EXPECT_EQ(replay.successor_of(5), std::optional<std::size_t>(6));
  EXPECT_EQ(replay.successor_of(4), std::optional<std::size_t>(5));
  config.n_step = 2;
  const learner::Minibatch b = learner::assemble_minibatch(replay, replay::Sample{{0, 4}, {1.0, 1.0}}, config);
  EXPECT_FLOAT_EQ(b.reward[0], 99.0f);  // 0 + 0.99 * 100, terminal within 2
  EXPECT_FLOAT_EQ(b.discount[0], 0);
  EXPECT_FLOAT_EQ(b.reward[1], 0);  // 0 -> 5 -> 10: not terminal; bootstraps from frame 10 at step 2
  EXPECT_FLOAT_EQ(b.discount[1], 0.99f * 0.99f);
  EXPECT_FLOAT_EQ(b.next_proprio[1][3], 1.0f - 2.0f * 2 / 9);  // the time input of step 2
}

// Samples that reach the same frame at the same step reach the same state (one id: the targets
// evaluate it once); the same frame at another step is another state (another time input).
TEST(QLearner, SamplesReachingTheSameFrameAtTheSameStepShareTheirNextState) {
  learner::LearnerConfig config = small_config();
  replay::ReplayBuffer replay;
  const Eigen::Vector3f block(0.1f, -0.2f, 0.78f);
  for (int32_t f : {0, 5, 10}) replay.add(frame(4, f, block, 220));
  for (auto [from, step] : {std::pair{0, 0}, std::pair{5, 0}, std::pair{5, 1}}) {  // all three into frame 10
    stream::Record t = transition(config.hierarchy, 4, {0.1, -0.2, 0.8}, false);
    t.set_scalar<int32_t>("frame", from);
    t.set_scalar<int32_t>("next_frame", 10);
    t.set_scalar<int32_t>("step", step);
    replay.add(t);
  }
  const learner::Minibatch b = learner::assemble_minibatch(replay, replay::Sample{{0, 1, 2, 0}, {1, 1, 1, 1}}, config);
  ASSERT_EQ(b.next_state.size(), 4u);
  EXPECT_EQ(b.next_state[0], b.next_state[1]);  // frame 10 at step 1
  EXPECT_EQ(b.next_state[0], b.next_state[3]);  // the same transition twice
  EXPECT_NE(b.next_state[0], b.next_state[2]);  // frame 10 at step 2
}

namespace {

std::vector<float> gradient_values(const std::vector<nets::QAttentionNet>& nets, int depth) {
  std::vector<float> all;
  for (const auto& p : nets[depth].module().parameters()) {
    if (!p.grad().defined()) continue;
    const auto g = p.grad().contiguous();
    all.insert(all.end(), g.data_ptr<float>(), g.data_ptr<float>() + g.numel());
  }
  return all;
}

double huber(double x) { return std::abs(x) < 1 ? 0.5 * x * x : std::abs(x) - 0.5; }

// A learner of `config` with weights from `seed`, and the tiny replay as one batch.
struct Seeded {
  replay::ReplayBuffer replay;
  learner::QLearner trainer;
  learner::Minibatch batch;
  Seeded(const learner::LearnerConfig& config, uint64_t seed)
      : replay(tiny_replay(config)), trainer((nets::set_torch_threads(2), nets::seed_torch(seed), config)),
        batch(learner::assemble_minibatch(replay, all_of(replay), config)) {}
};

}  // namespace

// Published: every gradient element clipped to +-0.01, each depth's network on its own.
TEST(QLearner, GradientsAreClippedByValuePerDepth) {
  nets::set_torch_threads(2);
  for (double clip : {0.0, 0.01}) {
    SCOPED_TRACE("clip " + std::to_string(clip));
    learner::LearnerConfig config = small_config();
    config.grad_clip_value = clip;
    Seeded s(config, 17);
    s.trainer.gradients(s.batch);
    const learner::QLearner& learner = s.trainer;
    for (int d = 0; d < 2; ++d) {
      const std::vector<float> g = gradient_values(learner.online(), d);
      ASSERT_FALSE(g.empty());
      float largest = 0;
      int at_bound = 0;
      for (float x : g) {
        largest = std::max(largest, std::abs(x));
        at_bound += std::abs(std::abs(x) - 0.01f) < 1e-9f;
      }
      if (clip > 0) {
        EXPECT_LE(largest, 0.01f + 1e-9f) << "depth " << d;
        EXPECT_GT(at_bound, 0) << "depth " << d << ": nothing was clipped, the case shows nothing";
      } else {
        EXPECT_GT(largest, 0.01f) << "depth " << d << ": unclipped gradients this small show nothing";
      }
    }
  }
}

// The loss against one written out here from the networks' outputs: per sample the Huber TD
// error (at the last depth the mean of translation, three rotation axes and gripper) plus
// lambda * (mean |translation Q| + at the last depth mean |the head's 218 outputs|), weighted
// by the importance weights, then the batch mean.
// The loss of one step computed by hand from the networks' outputs, per depth: the Huber TD
// loss of the taken action (at the last depth a mean over translation, three rotation axes and
// the gripper), lambda * mean|Q|, and on a demonstration's sample the large margins
// max_a [Q(a) + m [a != taken]] - Q(taken) by a loop over every action, meant like the TD loss.
// With heads_at_taken_voxel, the last depth's rotation and gripper Q values are those of the
// head reading each transition's own voxel (HeadInput::voxel), not the greedy one.
std::vector<double> loss_by_hand(learner::QLearner& learner, const learner::Minibatch& batch, double q_reg, double m,
                                 bool heads_at_taken_voxel = false) {
  const learner::Targets targets = learner.targets(batch);
  const int n = batch.size, cells = V * V * V;
  const auto margin = [&](const float* q, int count, int64_t taken) {
    double most = -1e30;
    for (int a = 0; a < count; ++a) most = std::max(most, q[a] + (a == taken ? 0.0 : m));
    return most - q[taken];
  };
  std::vector<double> losses;
  for (int d = 0; d < 2; ++d) {
    nets::QValues q = learner.online()[d].predict(batch.grids[d].data(), batch.proprio.data(), n);
    if (d == 1 && heads_at_taken_voxel) {
      torch::NoGradGuard no_grad;
      const int channels = learner.online()[d].config().channels;
      const auto grid = torch::from_blob(const_cast<float*>(batch.grids[d].data()), {n, V, V, V, channels});
      const auto proprio = torch::from_blob(const_cast<float*>(batch.proprio.data()), {n, 4});
      std::vector<int64_t> voxels(batch.voxel[d].begin(), batch.voxel[d].end());
      const nets::QOutputs out = learner.online()[d].module().forward(nets::channels_first(grid), proprio,
                                                                       torch::tensor(voxels, torch::kLong));
      const auto rotation = out.rotation.contiguous(), gripper = out.gripper.contiguous();
      q.rotation.assign(rotation.data_ptr<float>(), rotation.data_ptr<float>() + rotation.numel());
      q.gripper.assign(gripper.data_ptr<float>(), gripper.data_ptr<float>() + gripper.numel());
    }
    double loss = 0;
    for (int i = 0; i < n; ++i) {
      const float* t = q.translation.data() + static_cast<std::size_t>(i) * cells;
      double td = huber(t[batch.voxel[d][i]] - targets.translation[d][i]);
      double margins = margin(t, cells, batch.voxel[d][i]);
      double reg = 0;
      for (int c = 0; c < cells; ++c) reg += std::abs(t[c]) / cells;
      if (d == 1) {
        double head_reg = 0;
        for (int axis = 0; axis < 3; ++axis) {
          const float* r = q.rotation.data() + (static_cast<std::size_t>(i) * 3 + axis) * 72;
          td += huber(r[batch.rotation_bins[3 * i + axis]] - targets.rotation[3 * i + axis]);
          margins += margin(r, 72, batch.rotation_bins[3 * i + axis]);
          for (int b = 0; b < 72; ++b) head_reg += std::abs(r[b]) / 218;
        }
        const float* g = q.gripper.data() + static_cast<std::size_t>(i) * 2;
        td += huber(g[batch.gripper[i]] - targets.gripper[i]);
        margins += margin(g, 2, batch.gripper[i]);
        head_reg += (std::abs(g[0]) + std::abs(g[1])) / 218;
        td /= 5;
        margins /= 5;
        reg += head_reg;
      }
      const double demo_margins = m > 0 && batch.demo[i] != 0 ? margins : 0.0;
      loss += batch.weights[i] * (td + demo_margins + q_reg * reg) / n;
    }
    losses.push_back(loss);
  }
  return losses;
}

TEST(QLearner, LossIsOneMeanOverFiveTermsAndRegularisedWithImportanceWeights) {
  learner::LearnerConfig config = small_config();
  config.q_regularisation = 0.7;
  Seeded s(config, 19);
  s.batch.weights = {1.0, 0.5, 0.25, 0.75};
  const std::vector<double> expected = loss_by_hand(s.trainer, s.batch, 0.7, 0);
  const learner::StepStats stats = s.trainer.gradients(s.batch);
  for (int d = 0; d < 2; ++d)
    EXPECT_NEAR(stats.depth_loss[d], expected[d], 1e-5 * std::abs(expected[d]) + 1e-7) << "depth " << d;
  EXPECT_NEAR(stats.loss, expected[0] + expected[1], 1e-5 * std::abs(expected[0] + expected[1]));
}

// --demo-margin: DQfD's large margins on the demonstrations' samples only; the margin is large
// enough that the untrained networks' other actions are within it, so every head adds a term.
TEST(QLearner, DemoMarginAddsTheLargeMarginsOfTheDemonstrationsOnly) {
  learner::LearnerConfig config = small_config();
  config.demo_margin = 0.4;
  Seeded s(config, 19);
  ASSERT_EQ(s.batch.size, 4);
  s.batch.demo = {1, 0, 1, 0};  // the tiny replay's own flags aside: two of each
  s.batch.weights = {1.0, 0.5, 0.25, 0.75};
  const std::vector<double> with = loss_by_hand(s.trainer, s.batch, 1.0, 0.4);
  const std::vector<double> without = loss_by_hand(s.trainer, s.batch, 1.0, 0);
  const learner::StepStats stats = s.trainer.gradients(s.batch);
  for (int d = 0; d < 2; ++d) {
    EXPECT_NEAR(stats.depth_loss[d], with[d], 1e-5 * std::abs(with[d]) + 1e-7) << "depth " << d;
    EXPECT_GT(with[d], without[d] + 0.01) << "depth " << d;  // the margins are there to be learned
  }
  // Not a setting older checkpoints lack: the JSON names it only when it is used.
  EXPECT_NE(config.json().find("\"demo_margin\": 0.4"), std::string::npos);
  EXPECT_EQ(small_config().json().find("demo_margin"), std::string::npos);
}

// --head-input voxel: the head the learner trains reads each transition's own voxel, so its
// rotation Q values are those of the place the transition went to; the greedy voxel's differ.
TEST(QLearner, VoxelHeadIsTrainedAtTheTransitionsVoxel) {
  learner::LearnerConfig config = small_config();
  config.net.head_input = nets::HeadInput::voxel;
  Seeded s(config, 19);
  const std::vector<double> taken = loss_by_hand(s.trainer, s.batch, 1.0, 0, true);
  const std::vector<double> greedy = loss_by_hand(s.trainer, s.batch, 1.0, 0, false);
  const learner::StepStats stats = s.trainer.gradients(s.batch);
  EXPECT_NEAR(stats.depth_loss[0], taken[0], 1e-5 * std::abs(taken[0]) + 1e-7);
  EXPECT_NEAR(stats.depth_loss[1], taken[1], 1e-5 * std::abs(taken[1]) + 1e-7);
  EXPECT_GT(std::abs(taken[1] - greedy[1]), 1e-4) << "the batch's voxels are the greedy ones: the case shows nothing";
  EXPECT_NE(config.json().find("\"head_input\": \"voxel\""), std::string::npos);
  EXPECT_EQ(small_config().json().find("head_input"), std::string::npos);
  config.net.architecture = nets::Architecture::arm;
  EXPECT_THROW(config.validate(), UsageError);
}

// The metrics' agreement columns: per rotation axis and for the gripper, the share of the
// batch whose greedy bin is the transition's own, counted here from the networks' outputs on a
// batch whose actions are made to agree with the greedy bins in a known pattern; and the mean
// Huber loss of the rotation terms, from the same outputs and targets.
TEST(QLearner, HeadAgreementIsTheShareOfTheBatchWhoseGreedyBinIsTheTransitions) {
  Seeded s(small_config(), 23);
  const int n = s.batch.size;
  const nets::QValues q = s.trainer.online()[1].predict(s.batch.grids[1].data(), s.batch.proprio.data(), n);
  const auto greedy = [](const float* v, int count) { return static_cast<int>(std::max_element(v, v + count) - v); };
  std::vector<double> agree(4, 0.0);
  for (int i = 0; i < n; ++i) {
    for (int axis = 0; axis < 3; ++axis) {
      const int best = greedy(q.rotation.data() + (static_cast<std::size_t>(i) * 3 + axis) * 72, 72);
      const bool same = (i + axis) % 3 != 0;
      s.batch.rotation_bins[3 * i + axis] = same ? best : (best + 5) % 72;
      agree[axis] += same ? 1.0 / n : 0.0;
    }
    const int best = greedy(q.gripper.data() + static_cast<std::size_t>(i) * 2, 2);
    s.batch.gripper[i] = i == 0 ? best : 1 - best;
    agree[3] += i == 0 ? 1.0 / n : 0.0;
  }
  const learner::Targets targets = s.trainer.targets(s.batch);
  double rotation_loss = 0;
  for (int i = 0; i < n; ++i)
    for (int axis = 0; axis < 3; ++axis) {
      const float* r = q.rotation.data() + (static_cast<std::size_t>(i) * 3 + axis) * 72;
      rotation_loss += huber(r[s.batch.rotation_bins[3 * i + axis]] - targets.rotation[3 * i + axis]) / (3 * n);
    }
  const learner::StepStats stats = s.trainer.gradients(s.batch);
  ASSERT_EQ(stats.head_agreement.size(), 4u);
  for (int k = 0; k < 4; ++k) EXPECT_DOUBLE_EQ(stats.head_agreement[k], agree[k]) << "column " << k;
  EXPECT_NE(agree[0], agree[1]) << "every axis agrees alike: the case shows nothing";
  EXPECT_NEAR(stats.rotation_loss, rotation_loss, 1e-5 * rotation_loss + 1e-7);
}

// --demo-cross-entropy: on the demonstrations' samples only, W times the mean over the head's
// four outputs (three rotation axes, the gripper) of -log softmax at the demonstrated bin,
// worked out here from the networks' outputs by a loop over the bins; the translation depths
// are untouched.
TEST(QLearner, DemoCrossEntropyAddsTheHeadsLogLossOnTheDemonstrationsOnly) {
  learner::LearnerConfig config = small_config();
  config.demo_cross_entropy = 0.25;
  Seeded s(config, 19);
  ASSERT_EQ(s.batch.size, 4);
  const int n = s.batch.size;
  s.batch.demo = {1, 0, 1, 0};
  s.batch.weights = {1.0, 0.5, 0.25, 0.75};
  const std::vector<double> plain = loss_by_hand(s.trainer, s.batch, 1.0, 0);
  const nets::QValues q = s.trainer.online()[1].predict(s.batch.grids[1].data(), s.batch.proprio.data(), n);
  const auto minus_log_softmax = [](const float* v, int count, int taken) {
    double sum = 0;
    for (int b = 0; b < count; ++b) sum += std::exp(static_cast<double>(v[b]));
    return std::log(sum) - v[taken];
  };
  double extra = 0;
  for (int i = 0; i < n; ++i) {
    if (s.batch.demo[i] == 0) continue;
    double ce = 0;
    for (int axis = 0; axis < 3; ++axis)
      ce += minus_log_softmax(q.rotation.data() + (static_cast<std::size_t>(i) * 3 + axis) * 72, 72,
                              static_cast<int>(s.batch.rotation_bins[3 * i + axis]));
    ce += minus_log_softmax(q.gripper.data() + static_cast<std::size_t>(i) * 2, 2, static_cast<int>(s.batch.gripper[i]));
    extra += s.batch.weights[i] * 0.25 * (ce / 4) / n;
  }
  const learner::StepStats stats = s.trainer.gradients(s.batch);
  EXPECT_NEAR(stats.depth_loss[0], plain[0], 1e-5 * std::abs(plain[0]) + 1e-7);
  EXPECT_NEAR(stats.depth_loss[1], plain[1] + extra, 1e-5 * (plain[1] + extra));
  EXPECT_GT(extra, 0.1) << "72 bins near uniform cost about log 72: a smaller term shows nothing";
  EXPECT_NE(config.json().find("\"demo_cross_entropy\": 0.25"), std::string::npos);
  EXPECT_EQ(small_config().json().find("demo_cross_entropy"), std::string::npos);
}

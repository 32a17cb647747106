// The learner's run: the pacing rule, and a followed replay whose steps depend on what the
// inputs hold, not on when it arrived.
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "common/error.hpp"
#include "learner/training_loop.hpp"
#include "learner_fixtures.hpp"
#include "stream/reader.hpp"
#include "stream/writer.hpp"

using namespace qte;
using namespace qte::test_support;

TEST(Pacing, EachStepNeedsTheFewestAgentTransitionsThatAllowIt) {
  for (double ratio : {0.1, 0.25, 0.3, 0.5, 1.0, 2.0, 3.0}) {
    for (int64_t pretrain : {0, 5}) {
      learner::LoopOptions o;
      o.replay_ratio = ratio;
      o.pretrain = pretrain;
      for (int64_t step = 0; step < 300; ++step) {
        const int64_t n = learner::transitions_needed(o, step);
        SCOPED_TRACE("ratio " + std::to_string(ratio) + ", pretrain " + std::to_string(pretrain) + ", step " +
                     std::to_string(step) + ": needs " + std::to_string(n));
        EXPECT_GT(learner::allowed_steps(o, n), step);
        if (n > 0) {
          EXPECT_LE(learner::allowed_steps(o, n - 1), step);
        }
        if (step < pretrain) {
          EXPECT_EQ(n, 0);
        }
      }
    }
  }
  learner::LoopOptions none;
  none.replay_ratio = 0;
  EXPECT_EQ(learner::transitions_needed(none, 0), INT64_MAX);
}

namespace {

// A replay file: the four demonstration episodes, then `agent` transitions of the agent's own.
void write_replay(const std::string& path, const learner::LearnerConfig& config, int agent) {
  stream::RecordWriter writer(path);
  const Eigen::Vector3f blocks[2] = {{0.1f, -0.2f, 0.78f}, {0.3f, 0.2f, 0.78f}};
  for (int e = 0; e < 4 + agent; ++e) {
    const Eigen::Vector3f& block = blocks[e % 2];
    writer.write(frame(e, 0, block, 220));
    writer.write(frame(e, 1, block, 220));
    stream::Record t = transition(config.hierarchy, e, block.cast<double>(), e % 3 == 0);
    t.set_scalar<uint8_t>("demo", e < 4);
    writer.write(t);
  }
  writer.close();
}

struct FollowedRun {
  int64_t steps = 0, transitions_read = 0;
  std::string metrics;
};

FollowedRun follow(const std::string& dir, int agent_transitions) {
  std::filesystem::create_directories(dir);
  learner::LearnerConfig config;
  config.batch = 2;
  write_replay(dir + "/replay.rec", config, agent_transitions);
  std::ofstream(dir + "/stop").put('\n');
  learner::LoopOptions o;
  o.steps = 1000;
  o.start_after = 1;
  o.pretrain = 1;
  o.replay_ratio = 0.5;
  o.follow = true;
  o.stop_file = dir + "/stop";
  o.checkpoint_every = 1000;
  o.log_every = 1;
  o.metrics_path = dir + "/metrics.csv";
  o.poll = std::chrono::milliseconds(10);
  nets::set_torch_threads(2);
  nets::seed_torch(3);
  learner::QLearner learner(config);
  replay::ReplayBuffer replay;
  learner::CheckpointDirectory checkpoints(dir + "/ckpt", 2);
  learner::InputFollower inputs({dir + "/replay.rec"}, true);
  std::ostringstream progress;
  learner::TrainingLoop loop(learner, replay, inputs, checkpoints, o, progress);
  EXPECT_FALSE(loop.start(false));
  loop.run();
  FollowedRun r;
  r.steps = learner.step();
  r.transitions_read = loop.transitions_read();
  std::ifstream in(o.metrics_path);
  r.metrics.assign(std::istreambuf_iterator<char>(in), {});
  return r;
}

}  // namespace

TEST(TrainingLoop, FollowTakesTheStepsTheReplayRatioAllowsAndStops) {
  const std::string dir = (std::filesystem::temp_directory_path() / ("qte_loop_" + std::to_string(::getpid()))).string();
  const FollowedRun two = follow(dir + "/two", 2), six = follow(dir + "/six", 6);
  EXPECT_EQ(two.steps, 1 + 1);  // --pretrain 1, then 0.5 per agent transition
  EXPECT_EQ(six.steps, 1 + 3);
  EXPECT_EQ(six.transitions_read, 4 + 6);
  std::istringstream rows(six.metrics);
  std::string header, line;
  std::getline(rows, header);
  EXPECT_EQ(header.rfind("step,transitions,agent_transitions,replay,demos,loss", 0), 0u) << header;
  const auto fields = [](const std::string& text) {
    std::vector<std::string> out;
    std::istringstream in(text);
    for (std::string f; std::getline(in, f, ',');) out.push_back(f);
    return out;
  };
  const std::vector<std::string> names = fields(header);
  const auto column = [&](const std::string& name) { return std::find(names.begin(), names.end(), name) - names.begin(); };
  int count = 0;
  while (std::getline(rows, line)) {
    ++count;
    const std::vector<std::string> row = fields(line);
    ASSERT_EQ(row.size(), names.size()) << line;
    for (const char* name : {"agree_rotation_x", "agree_rotation_y", "agree_rotation_z", "agree_gripper"}) {
      ASSERT_LT(column(name), static_cast<long>(names.size())) << name << " missing from " << header;
      const double share = std::stod(row[column(name)]);
      EXPECT_TRUE(share >= 0 && share <= 1) << name << " " << share;
    }
    EXPECT_GE(std::stod(row[column("loss_rotation")]), 0.0);
  }
  EXPECT_EQ(count, 4);
  // The checkpoint of the last step holds the loop's state.
  stream::RecordReader reader(dir + "/six/ckpt/latest.rec");
  reader.next();
  reader.next();
  const auto state = reader.next();
  ASSERT_TRUE(state.has_value());
  EXPECT_EQ(state->scalar<int64_t>("step"), 4);
  EXPECT_EQ(state->scalar<int64_t>("agent_transitions"), 6);
  EXPECT_GT(state->scalar<double>("max_priority"), 0);
  std::filesystem::remove_all(dir);
}

// Sizes a run cannot hold are refused before anything is allocated (a batch of 100,000 grew
// to 24 GB until the kernel killed it; a tree target of 100,000 branches ran for minutes).
TEST(LearnerConfig, StepsThatCannotFitInMemoryAreRefused) {
  learner::LearnerConfig config;
  const double machine = 24e9;
  EXPECT_NO_THROW(config.check_memory(machine));  // the defaults
  config.tree_target_k = 10;
  EXPECT_NO_THROW(config.check_memory(machine));  // the published K
  config.batch = 128;
  EXPECT_NO_THROW(config.check_memory(machine));  // the published batch
  config.batch = 100000;
  EXPECT_THROW(config.check_memory(machine), UsageError);
  config.batch = 32;
  config.tree_target_k = 100000;
  try {
    config.check_memory(machine);
    FAIL() << "a 100,000-branch tree target was accepted";
  } catch (const UsageError& e) {
    EXPECT_NE(std::string(e.what()).find("GB per step; this machine has 24 GB"), std::string::npos) << e.what();
  }
  learner::LearnerConfig arm;
  arm.net.architecture = nets::Architecture::arm;
  arm.net.base_channels = 64;
  EXPECT_GT(arm.step_memory_bytes(), 10 * config.batch * 1e6);
}

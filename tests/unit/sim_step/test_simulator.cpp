// The sim-step loop: resets, trajectories, failures, determinism and the tasks' experts.
#include <gtest/gtest.h>

#include <chrono>
#include <fstream>
#include <set>

#include "common/random.hpp"
#include "robot/pose_values.hpp"
#include "trajectory_helpers.hpp"
#include "stream/codec.hpp"
#include "tasks/task.hpp"
#include "test_support.hpp"

using namespace qte;
using namespace qte::sim_step;

namespace {

using test_support::xarm;

SimulatorOptions small_options() {
  SimulatorOptions options;
  options.cameras = {{"front", {}}};
  options.cameras[0].intrinsics.width = options.cameras[0].intrinsics.height = 32;
  options.render_threads = 1;
  return options;
}

stream::Record reset_record(const std::string& task, int variation, int64_t seed) {
  stream::Record r("reset");
  r.set_string("task", task);
  r.set_scalar<int32_t>("variation", variation);
  r.set_scalar<int64_t>("seed", seed);
  return r;
}

struct SimRun {
  Simulator simulator{xarm(), small_options()};
  std::vector<stream::Record> out;
  void send(const stream::Record& r) {
    simulator.handle(r, [&](const stream::Record& obs) { out.push_back(obs); });
  }
  const stream::Record& last() const { return out.back(); }
};

// Executes the task's expert with straight joint moves; returns the final observation.
stream::Record run_expert(SimRun& run, const std::string& task, int variation, int64_t seed) {
  run.send(reset_record(task, variation, seed));
  for (const auto& waypoint : run.simulator.task()->expert_waypoints(*run.simulator.world())) {
    world::World& world = *run.simulator.world();
    const robot::JointVector q = test_support::ik_world(world, waypoint.tcp_pose);
    run.send(test_support::straight_trajectory(xarm(), world.joint_positions(), q, waypoint.gripper_open));
    if (run.simulator.episode_over()) break;
  }
  return run.last();
}

}  // namespace

TEST(Simulator, ResetWritesAFullObservation) {
  SimRun run;
  run.send(reset_record("reach_target", 0, 1));
  ASSERT_EQ(run.out.size(), 1u);
  const auto& obs = run.last();
  EXPECT_EQ(obs.array<uint8_t>("front.rgb").shape, (stream::Shape{32, 32, 3}));
  EXPECT_EQ(obs.array<float>("front.depth").shape, (stream::Shape{32, 32}));
  EXPECT_EQ(obs.array<float>("front.points").shape, (stream::Shape{32, 32, 3}));
  EXPECT_EQ(obs.array<double>("front.intrinsics").shape, (stream::Shape{3, 3}));
  EXPECT_EQ(obs.array<double>("joint_positions").size(), 7);
  EXPECT_EQ(obs.scalar<int32_t>("step"), 0);
  EXPECT_EQ(obs.scalar<uint8_t>("terminal"), 0);
  EXPECT_EQ(obs.scalar<int32_t>("episode_length"), 10);
  EXPECT_EQ(obs.scalar<uint8_t>("gripper_open"), 1);
  EXPECT_EQ(obs.string("task"), "reach_target");
}

TEST(Simulator, SameSeedSameBytesOtherSeedOtherScene) {
  auto bytes = [](int64_t seed) {
    SimRun run;
    run.send(reset_record("pick_and_lift", 2, seed));
    return stream::encode_record(run.last());
  };
  EXPECT_EQ(bytes(7), bytes(7));
  EXPECT_NE(bytes(7), bytes(8));
}

TEST(Simulator, ObjectsAreWrittenOnlyWhenAskedWithTheirRolesPosesAndBoxes) {
  SimRun plain;
  plain.send(reset_record("lift_numbered_block", 2, 3));
  EXPECT_FALSE(plain.last().has("objects.pose"));  // observations as agents see them
  EXPECT_FALSE(plain.last().has("objects.names"));

  auto asked = [] {
    SimulatorOptions options = small_options();
    options.object_poses = true;
    return options;
  };
  Simulator simulator(xarm(), asked());
  std::vector<stream::Record> out;
  simulator.handle(reset_record("lift_numbered_block", 2, 3), [&](const stream::Record& r) { out.push_back(r); });
  const stream::Record& obs = out.back();
  EXPECT_EQ(obs.string("objects.names"), "block1,block2,block3");
  const auto role = obs.array<uint8_t>("objects.role");
  ASSERT_EQ(role.shape, (stream::Shape{3}));
  EXPECT_EQ(std::vector<uint8_t>(role.begin(), role.end()), (std::vector<uint8_t>{2, 2, 1}));  // block 3 the target
  const auto pose = obs.array<double>("objects.pose");
  const auto box = obs.array<double>("objects.box");
  ASSERT_EQ(pose.shape, (stream::Shape{3, 7}));
  ASSERT_EQ(box.shape, (stream::Shape{3, 6}));
  const world::World& world = *simulator.world();
  for (int id = 0; id < 3; ++id) {
    const Eigen::Isometry3d p = world.object_pose(id);
    for (int k = 0; k < 3; ++k) EXPECT_EQ(pose[id * 7 + k], p.translation()[k]);
    EXPECT_NEAR(std::abs(Eigen::Quaterniond(p.linear()).dot(robot::quaternion_of(&pose[id * 7]))), 1.0, 1e-6);
    for (int k = 0; k < 3; ++k) {  // a 5 cm block about its centre
      EXPECT_DOUBLE_EQ(box[id * 6 + k], -0.025);
      EXPECT_DOUBLE_EQ(box[id * 6 + 3 + k], 0.025);
    }
  }
  // The same scene with them: the same images, and the same bytes every time.
  Simulator again(xarm(), asked());
  std::vector<stream::Record> out_again;
  again.handle(reset_record("lift_numbered_block", 2, 3), [&](const stream::Record& r) { out_again.push_back(r); });
  EXPECT_EQ(stream::encode_record(out_again.back()), stream::encode_record(obs));
  const auto rgb = obs.array<uint8_t>("front.rgb"), plain_rgb = plain.last().array<uint8_t>("front.rgb");
  EXPECT_TRUE(std::equal(rgb.begin(), rgb.end(), plain_rgb.begin()));
}

TEST(Simulator, UnknownTaskIsAnErrorListingTheTasks) {
  SimRun run;
  try {
    run.send(reset_record("open_drawer", 0, 1));
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("known tasks: reach_target, pick_and_lift, lift_numbered_block, reach_prism, pick_and_lift_small, stack_blocks, setup_checkers"),
              std::string::npos);
    EXPECT_NE(std::string(e.what()).find("'reset' record, field 'task'"), std::string::npos) << e.what();
  }
}

TEST(Simulator, BadTrajectoriesFailTheActionWithAReason) {
  auto failure_of = [](const std::function<stream::Record(const world::World&)>& make) {
    SimRun run;
    run.send(reset_record("reach_target", 0, 1));
    run.send(make(*run.simulator.world()));
    EXPECT_EQ(run.last().scalar<uint8_t>("terminal"), 1);
    EXPECT_EQ(run.last().scalar<float>("reward"), 0.0f);
    return run.last().has("failure") ? run.last().string("failure") : std::string("none");
  };
  const auto& robot = xarm();
  // Not starting at the current joint positions.
  EXPECT_NE(failure_of([&](const world::World& w) {
              robot::JointVector elsewhere = w.joint_positions();
              elsewhere[0] += 0.3;
              return test_support::straight_trajectory(robot, elsewhere, elsewhere, true);
            }).find("does not start"), std::string::npos);
  // NaN.
  EXPECT_NE(failure_of([&](const world::World& w) {
              robot::JointVector q = w.joint_positions();
              q[2] = NAN;
              return test_support::straight_trajectory(robot, w.joint_positions(), q, true);
            }).find("not_finite"), std::string::npos);
  // Beyond a joint limit (joint 2: -118..120 deg).
  EXPECT_EQ(failure_of([&](const world::World& w) {
              robot::JointVector q = w.joint_positions();
              q[1] = 2.3;
              return test_support::straight_trajectory(robot, w.joint_positions(), q, true);
            }), "joint_limits:joint2");
  // Into the table.
  EXPECT_NE(failure_of([&](const world::World& w) {
              robot::JointVector q = w.joint_positions();
              q[1] = 1.6;  // shoulder forward and down: the arm sweeps into the table
              q[3] = 0.2;
              return test_support::straight_trajectory(robot, w.joint_positions(), q, true);
            }).find("-table"), std::string::npos);
  // Valid but endless: a trajectory longer than a next-best pose may take fails at once
  // (it used to run for minutes, and from ~1e8 s overflowed the control-step count).
  for (double end_s : {1e5, 1e9, 1e300}) {
    const auto started = std::chrono::steady_clock::now();
    EXPECT_EQ(failure_of([&](const world::World& w) {
                stream::Record t = test_support::straight_trajectory(robot, w.joint_positions(), w.joint_positions(), true);
                t.set<double>("time_s", {2}, std::vector<double>{0, end_s});
                return t;
              }).rfind("invalid_trajectory:longer than", 0), 0u) << end_s;
    EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count(), 10.0);
  }
  // A planner failure passed on.
  EXPECT_EQ(failure_of([](const world::World&) {
              stream::Record t("trajectory");
              t.set_string("failure", "ik_failed");
              return t;
            }), "ik_failed");
}

TEST(Simulator, SelfCollisionFailsTheAction) {
  SimRun run;
  run.send(reset_record("reach_target", 0, 1));
  world::World& world = *run.simulator.world();
  // Elbow folded far back (joint 4 at 194 deg) with the wrist bent back (joint 6 at 174
  // deg): the wrist comes down onto the forearm.
  robot::JointVector q;
  q << 0, -0.01, 0, 3.39, 0, 3.04, 0;
  run.send(test_support::straight_trajectory(xarm(), world.joint_positions(), q, true));
  ASSERT_TRUE(run.last().has("failure"));
  const std::string failure = run.last().string("failure");
  EXPECT_EQ(failure.rfind("collision:", 0), 0u) << failure;
  EXPECT_EQ(failure.find("table"), std::string::npos) << failure;
  EXPECT_EQ(run.last().scalar<uint8_t>("terminal"), 1);
}

TEST(Simulator, ProtocolErrorsNameTheRecord) {
  SimRun run;
  EXPECT_THROW(run.send(test_support::straight_trajectory(xarm(), robot::JointVector::Zero(),
                                                     robot::JointVector::Zero(), true)),
               StreamError);
}

TEST(Simulator, GraspHoldsThroughLiftingAndOpeningReleases) {
  SimRun run;
  run.send(reset_record("pick_and_lift", 0, 3));
  world::World& world = *run.simulator.world();
  const auto waypoints = run.simulator.task()->expert_waypoints(world);
  const int block = world.object_id("target");
  const double z0 = world.object_pose(block).translation().z();
  for (int i = 0; i < 2; ++i)  // above, grasp (close)
    run.send(test_support::straight_trajectory(xarm(), world.joint_positions(),
                                               test_support::ik_world(world, waypoints[i].tcp_pose),
                                               waypoints[i].gripper_open));
  // Lift by 20 cm, then carry it 10 cm sideways.
  Eigen::Isometry3d lifted = waypoints[1].tcp_pose;
  lifted.translation().z() += 0.20;
  run.send(test_support::straight_trajectory(xarm(), world.joint_positions(),
                                             test_support::ik_world(world, lifted), false));
  EXPECT_EQ(world.held_object(), block);
  EXPECT_NEAR(world.object_pose(block).translation().z(), z0 + 0.20, 0.005);
  lifted.translation().y() += 0.10;
  run.send(test_support::straight_trajectory(xarm(), world.joint_positions(),
                                             test_support::ik_world(world, lifted), false));
  EXPECT_EQ(world.held_object(), block);
  EXPECT_NEAR((world.object_pose(block).translation() - lifted.translation()).norm(), 0.0, 0.005);
  EXPECT_LT(world.finger_opening_m(), 0.06);  // fingers stopped on the 5 cm block
  EXPECT_GT(world.finger_opening_m(), 0.045);
  world.open_gripper();
  world.settle(1.0);
  EXPECT_EQ(world.held_object(), -1);
  EXPECT_NEAR(world.object_pose(block).translation().z(), z0, 0.005);  // fell back to the table
}

// objects.held says which object the gripper holds: the cup after the expert's grasp, none
// after opening on it, none after closing on empty space, and no such field without --objects.
TEST(Simulator, ObjectsHeldSaysWhatTheGripperHolds) {
  SimulatorOptions options = small_options();
  options.object_poses = true;
  Simulator simulator(xarm(), options);
  std::vector<stream::Record> out;
  auto send = [&](const stream::Record& r) { simulator.handle(r, [&](const stream::Record& obs) { out.push_back(obs); }); };
  auto held = [&] {
    const auto h = out.back().array<uint8_t>("objects.held");
    EXPECT_EQ(h.shape, (stream::Shape{2}));  // the cup, the other cup
    return std::vector<uint8_t>(h.begin(), h.end());
  };
  auto move = [&](const Eigen::Isometry3d& pose, bool gripper_open) {
    world::World& world = *simulator.world();
    send(test_support::straight_trajectory(xarm(), world.joint_positions(), test_support::ik_world(world, pose),
                                           gripper_open));
  };
  send(reset_record("pick_up_cup", 0, 5));
  EXPECT_EQ(out.back().string("objects.names"), "cup,other_cup");
  EXPECT_EQ(held(), (std::vector<uint8_t>{0, 0}));
  const auto waypoints = simulator.task()->expert_waypoints(*simulator.world());
  move(waypoints[0].tcp_pose, true);   // above the cup
  move(waypoints[1].tcp_pose, false);  // grasp it
  EXPECT_EQ(held(), (std::vector<uint8_t>{1, 0}));
  move(waypoints[1].tcp_pose, true);   // open there: let go of it
  EXPECT_EQ(held(), (std::vector<uint8_t>{0, 0}));
  EXPECT_EQ(out.back().scalar<uint8_t>("success"), 0);

  send(reset_record("pick_up_cup", 0, 5));
  Eigen::Isometry3d empty = waypoints[1].tcp_pose;  // 12 cm beside the cup, the other cup 15 cm or more away
  const Eigen::Vector3d other = simulator.world()->object_pose(1).translation();
  const Eigen::Vector3d away = (empty.translation() - other).normalized();
  empty.translation() += 0.12 * Eigen::Vector3d(away.x(), away.y(), 0).normalized();
  Eigen::Isometry3d above = empty;
  above.translation().z() += 0.1;
  move(above, true);
  move(empty, false);
  EXPECT_FALSE(out.back().has("failure"));
  EXPECT_EQ(out.back().scalar<uint8_t>("gripper_open"), 0);
  EXPECT_EQ(held(), (std::vector<uint8_t>{0, 0}));
  EXPECT_LT(out.back().scalar<double>("gripper_opening_m"), 1e-6);  // closed on nothing

  SimRun plain;
  plain.send(reset_record("pick_up_cup", 0, 5));
  EXPECT_FALSE(plain.last().has("objects.held"));
}

TEST(Simulator, ObjectsArePushedByTheArm) {
  SimRun run;
  run.send(reset_record("pick_and_lift", 0, 3));
  world::World& world = *run.simulator.world();
  const int block = world.object_id("distractor1");
  const Eigen::Isometry3d start = world.object_pose(block);
  // Sweep the closed gripper through the block at half its height, along world y.
  Eigen::Isometry3d tcp = Eigen::Isometry3d::Identity();
  tcp.linear() = tasks::top_down(0);
  tcp.translation() = start.translation() + Eigen::Vector3d(0, -0.08, 0.0);
  world.close_gripper();
  run.send(test_support::straight_trajectory(xarm(), world.joint_positions(), test_support::ik_world(world, tcp), false));
  tcp.translation().y() += 0.16;
  run.send(test_support::straight_trajectory(xarm(), world.joint_positions(), test_support::ik_world(world, tcp), false));
  world.settle(0.5);
  EXPECT_GT((world.object_pose(block).translation() - start.translation()).norm(), 0.03);
}

class ExpertSolves : public ::testing::TestWithParam<std::string> {};

TEST_P(ExpertSolves, SeveralSeeds) {
  for (int64_t seed = 0; seed < 5; ++seed) {
    SimRun run;
    const int variation = static_cast<int>(seed % tasks::make_task(GetParam())->variation_count());
    const auto obs = run_expert(run, GetParam(), variation, seed);
    EXPECT_EQ(obs.scalar<uint8_t>("success"), 1)
        << GetParam() << " seed " << seed << (obs.has("failure") ? " failure " + obs.string("failure") : "");
    EXPECT_EQ(obs.scalar<float>("reward"), 100.0f);
    EXPECT_EQ(obs.scalar<uint8_t>("terminal"), 1);
  }
}

INSTANTIATE_TEST_SUITE_P(Tasks, ExpertSolves,
                         ::testing::Values("reach_target", "pick_and_lift", "lift_numbered_block", "reach_prism", "pick_and_lift_small",
                                           "stack_blocks", "setup_checkers"));

// Demonstration, exploration and evaluation scenes never meet, for any run seed: with the
// seeds examples/learn.sh gives (demo-record --seed S, sim-step --seed S * 100000 + chunk
// for exploration, --seed 1000000 for evaluation), and even when all three share one seed.
TEST(SceneSets, DemoExplorationAndEvaluationSeedsAreDisjointForSeedsZeroToNine) {
  std::set<uint64_t> eval;
  for (uint64_t e = 0; e < 50; ++e) eval.insert(scene_seed(1000000, SceneSet::eval, e));
  for (uint64_t run = 0; run < 10; ++run) {
    std::set<uint64_t> demo, explore;
    for (uint64_t e = 0; e < 100; ++e) demo.insert(scene_seed(run, SceneSet::demo, e));
    for (uint64_t chunk = 0; chunk < 50; ++chunk)
      for (uint64_t e = 0; e < 10; ++e) explore.insert(scene_seed(run * 100000 + chunk, SceneSet::explore, e));
    for (uint64_t e = 0; e < 50; ++e) eval.insert(scene_seed(run, SceneSet::eval, e));  // the same run seed too
    EXPECT_EQ(demo.size(), 100u);
    EXPECT_EQ(explore.size(), 500u);
    for (uint64_t s : demo) {
      EXPECT_EQ(scene_set_of(s), SceneSet::demo);
      EXPECT_FALSE(explore.count(s) || eval.count(s)) << "run " << run << ": demo scene " << s;
    }
    for (uint64_t s : explore) {
      EXPECT_EQ(scene_set_of(s), SceneSet::explore);
      EXPECT_FALSE(eval.count(s)) << "run " << run << ": exploration scene " << s;
    }
  }
  for (uint64_t s : eval) EXPECT_EQ(scene_set_of(s), SceneSet::eval);
  // The reset records carry them, and the seeds of old ('any') stay what they were.
  EpisodePlan plan{"reach_target", 0, 3, 0};
  plan.scenes = SceneSet::explore;
  EXPECT_EQ(static_cast<uint64_t>(plan_reset(plan, 2).scalar<int64_t>("seed")), scene_seed(0, SceneSet::explore, 2));
  EXPECT_EQ(scene_seed(5, SceneSet::any, 2), qte::derive_seed(5, 2));
  EXPECT_EQ(scene_set_from_name("eval"), SceneSet::eval);
  EXPECT_THROW(scene_set_from_name("test"), qte::UsageError);
}

// The sim-step stage with a plan: the first observation goes out before any input is read,
// the next episode starts right after a terminal observation, and after the planned episodes
// the stage reads no more.
TEST(SimStep, APlanStartsEpisodesByItselfAndEndsAfterThem) {
  Simulator simulator(xarm(), small_options());
  SimStep stage(simulator, EpisodePlan{"reach_target", 0, 2, 7});
  std::vector<stream::Record> out;
  int reads = 0;
  stream::run_stage(
      stage,
      [&]() -> std::optional<stream::Record> {
        EXPECT_FALSE(out.empty()) << "input read before the first observation";
        ++reads;
        // Not from the current joints: the action fails and the episode ends.
        return test_support::straight_trajectory(xarm(), robot::JointVector::Zero(), robot::JointVector::Ones(), true);
      },
      [&](const stream::Record& obs) { out.push_back(obs); });
  EXPECT_EQ(reads, 2);  // one failing action per episode, then done
  ASSERT_EQ(out.size(), 4u);
  for (int episode = 0; episode < 2; ++episode) {
    EXPECT_EQ(out[2 * episode].scalar<int32_t>("step"), 0);
    EXPECT_EQ(out[2 * episode + 1].scalar<uint8_t>("terminal"), 1);
    EXPECT_TRUE(out[2 * episode + 1].has("failure"));
  }
  EXPECT_EQ(out[0].scalar<int64_t>("episode_seed"), plan_reset(EpisodePlan{"reach_target", 0, 2, 7}, 0).scalar<int64_t>("seed"));
  EXPECT_EQ(out[2].scalar<int64_t>("episode_seed"), plan_reset(EpisodePlan{"reach_target", 0, 2, 7}, 1).scalar<int64_t>("seed"));
}

// Without a plan the stage is the simulator: nothing before the input, and it runs until the
// input ends.
TEST(SimStep, WithoutAPlanTheInputDrivesEverything) {
  Simulator simulator(xarm(), small_options());
  SimStep stage(simulator, std::nullopt);
  std::vector<stream::Record> in = {reset_record("reach_target", 0, 3), stream::Record("action"),
                                    reset_record("reach_target", 0, 4)};
  std::size_t next = 0;
  std::vector<stream::Record> out;
  stream::run_stage(
      stage,
      [&]() -> std::optional<stream::Record> {
        if (next == in.size()) return std::nullopt;
        return in[next++];
      },
      [&](const stream::Record& obs) { out.push_back(obs); });
  EXPECT_EQ(next, in.size());
  ASSERT_EQ(out.size(), 2u);  // one observation per reset; other records produce nothing
  EXPECT_FALSE(stage.done());
}

// In chunks: chunk c's episodes are those of the plan seeded seed + c, the stride picks this
// actor's chunks, the gate is asked before each chunk (and ends the stage when it says no),
// and it hears each chunk's environment steps once its last episode has ended.
TEST(SimStep, ChunksDrawTheirScenesFromTheirOwnSeedAndReportTheirSteps) {
  struct RecordingGate : ChunkGate {
    std::vector<int> opened;
    std::vector<std::pair<int, int>> finished_chunks;
    bool open(int chunk) override {
      opened.push_back(chunk);
      return opened.size() <= 2;  // two chunks, then no more
    }
    void finished(int chunk, int steps) override { finished_chunks.emplace_back(chunk, steps); }
  } gate;
  Simulator simulator(xarm(), small_options());
  const EpisodePlan plan{"reach_target", 0, 1000, 100};
  SimStep stage(simulator, plan, ChunkPlan{3, 1, 2}, gate);  // chunks 1, 3, 5, ... of 3 episodes
  std::vector<stream::Record> out;
  stream::run_stage(
      stage,
      [&]() -> std::optional<stream::Record> {  // a failing action: each episode is one step
        return test_support::straight_trajectory(xarm(), robot::JointVector::Zero(), robot::JointVector::Ones(), true);
      },
      [&](const stream::Record& obs) { out.push_back(obs); });
  EXPECT_TRUE(stage.done());
  EXPECT_EQ(gate.opened, (std::vector<int>{1, 3, 5}));
  EXPECT_EQ(gate.finished_chunks, (std::vector<std::pair<int, int>>{{1, 3}, {3, 3}}));
  ASSERT_EQ(out.size(), 12u);  // 2 chunks x 3 episodes x (reset + terminal observation)
  for (int chunk : {0, 1})
    for (int episode = 0; episode < 3; ++episode) {
      EpisodePlan chunk_plan = plan;
      chunk_plan.seed = plan.seed + (chunk == 0 ? 1 : 3);
      EXPECT_EQ(out[2 * (3 * chunk + episode)].scalar<int64_t>("episode_seed"),
                plan_reset(chunk_plan, episode).scalar<int64_t>("seed"))
          << "chunk " << chunk << " episode " << episode;
    }
}

// The gate of the learning loop's shell script: files in a directory.
TEST(SimStep, DirectoryGateOpensOnGoFilesStopsOnStopAndWritesSteps) {
  const std::string dir = test_support::temp_dir("gate");
  DirectoryGate gate(dir);
  EXPECT_EQ(gate.path(7, "go"), dir + "/0007.go");
  std::ofstream(gate.path(7, "go")).put('\n');
  EXPECT_TRUE(gate.open(7));
  gate.finished(7, 42);
  std::ifstream steps(gate.path(7, "steps"));
  int n = 0;
  steps >> n;
  EXPECT_EQ(n, 42);
  std::ofstream(dir + "/stop").put('\n');
  EXPECT_FALSE(gate.open(8));
}

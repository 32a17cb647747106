// Keyframe discovery case by case and on expert demonstrations, and the
// transitions' crop augmentation.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <set>

#include "common/error.hpp"
#include "demos/demo_recorder.hpp"
#include "keyframes/keyframes.hpp"
#include "keyframes/transitions.hpp"

using namespace qte;
using namespace qte::keyframes;

namespace {

// n frames moving (velocity 0.5) with the gripper open.
std::vector<FrameState> moving(int n) {
  std::vector<FrameState> frames(n);
  for (auto& f : frames) f.joint_velocities.fill(0.5);
  return frames;
}

void stop_at(std::vector<FrameState>& frames, int i) { frames[i].joint_velocities.fill(0.05); }

}  // namespace

TEST(Keyframes, GripperChangeAndLastFrame) {
  auto frames = moving(20);
  for (int i = 7; i < 20; ++i) frames[i].gripper_open = false;
  EXPECT_EQ(discover_keyframes(frames), (std::vector<int>{7, 19}));
}

TEST(Keyframes, StopsWithAFourFrameBuffer) {
  auto frames = moving(30);
  stop_at(frames, 10);
  stop_at(frames, 12);  // within the 4 frames after the stop at 10: not a keyframe
  stop_at(frames, 14);  // still within them (10 is among 10..13)
  stop_at(frames, 15);  // no stop among 11..14: a keyframe
  EXPECT_EQ(discover_keyframes(frames), (std::vector<int>{10, 15, 29}));
}

TEST(Keyframes, VelocityThresholdIsInclusiveAndPerJoint) {
  auto frames = moving(20);
  stop_at(frames, 5);
  frames[5].joint_velocities[6] = 0.1;   // exactly the threshold: still stopped
  stop_at(frames, 12);
  frames[12].joint_velocities[3] = -0.11;  // one joint over: moving
  EXPECT_EQ(discover_keyframes(frames), (std::vector<int>{5, 19}));
}

TEST(Keyframes, NoStopNextToAGripperChangeOrAtTheSecondToLastFrame) {
  auto frames = moving(20);
  for (int i = 9; i < 20; ++i) frames[i].gripper_open = false;
  stop_at(frames, 8);   // the gripper changes at 9: frame 8 is not a stop
  stop_at(frames, 10);  // frame 8 (i-2) still open: not a stop either
  stop_at(frames, 18);  // second-to-last: never a stop
  EXPECT_EQ(discover_keyframes(frames), (std::vector<int>{9, 19}));
}

TEST(Keyframes, AdjacentFinalKeyframesKeepTheLast) {
  auto frames = moving(12);
  stop_at(frames, 4);
  frames[10].gripper_open = false;  // keyframe at 10, and 11 is the last frame
  frames[11].gripper_open = false;
  EXPECT_EQ(discover_keyframes(frames), (std::vector<int>{4, 11}));
}

TEST(Keyframes, TooShortForAnything) {
  EXPECT_TRUE(discover_keyframes({}).empty());
  EXPECT_EQ(discover_keyframes(moving(1)), std::vector<int>{});
  EXPECT_EQ(discover_keyframes(moving(2)), std::vector<int>{1});
}

TEST(CropAugmentation, TheTargetStaysInsideTheDeeperGrid) {
  voxels::CoarseToFine h;
  std::mt19937 rng(8);
  std::uniform_real_distribution<double> u(0, 1), shift(-0.75 * h.offset_at(1), 0.75 * h.offset_at(1));
  for (int i = 0; i < 5000; ++i) {
    const Eigen::Vector3d target = h.scene.min_corner + Eigen::Vector3d(u(rng), u(rng), u(rng)) * h.scene.size_m;
    const std::vector<Eigen::Vector3d> shifts = {Eigen::Vector3d::Zero(), Eigen::Vector3d(shift(rng), shift(rng), shift(rng))};
    const auto indices = h.indices_of(target, shifts);
    const Eigen::Vector3d centre = h.scene.centre_of(indices[0]) + shifts[1];
    const voxels::GridBounds deeper = h.bounds_at(1, centre);
    EXPECT_TRUE(deeper.contains(deeper.index_of(target)));
    EXPECT_EQ(deeper.index_of(target), indices[1]);
  }
}

class ExpertKeyframes : public ::testing::TestWithParam<std::string> {};

TEST_P(ExpertKeyframes, MatchTheExpertsWaypoints) {
  const robot::RobotModel robot = robot::RobotModel::xarm7();
  demos::DemoOptions options;
  options.episodes = {GetParam(), 0, 3, 21};
  options.simulator.cameras[0].intrinsics.width = options.simulator.cameras[0].intrinsics.height = 32;
  options.simulator.render_threads = 1;
  std::vector<stream::Record> records;
  demos::record_demos(robot, options, [&](const stream::Record& r) { records.push_back(r); },
                      [](const std::string&) {});
  // The expert's waypoints of each episode, from a simulator reset the same way.
  sim_step::Simulator sim(robot, options.simulator);
  std::size_t at = 0;
  for (int e = 0; e < 3; ++e) {
    sim.handle(sim_step::plan_reset(options.episodes, e), [](const stream::Record&) {});
    const auto waypoints = sim.task()->expert_waypoints(*sim.world());
    std::vector<FrameState> states;
    std::vector<Eigen::Vector3d> positions;
    for (; records[at].type() == "obs"; ++at) {
      FrameState s;
      s.gripper_open = records[at].scalar<uint8_t>("gripper_open") != 0;
      const auto v = records[at].array<double>("joint_velocities");
      std::copy(v.begin(), v.end(), s.joint_velocities.begin());
      states.push_back(s);
      const auto p = records[at].array<double>("gripper_pose");
      positions.emplace_back(p[0], p[1], p[2]);
    }
    ASSERT_EQ(records[at].scalar<uint8_t>("success"), 1);
    ++at;  // the episode record
    const auto keyframes = discover_keyframes(states);
    ASSERT_EQ(keyframes.size(), waypoints.size()) << GetParam() << " episode " << e;
    for (std::size_t k = 0; k < keyframes.size(); ++k)
      EXPECT_LT((positions[keyframes[k]] - waypoints[k].tcp_pose.translation()).norm(), 0.01875)
          << GetParam() << " episode " << e << " keyframe " << k;
  }
}

INSTANTIATE_TEST_SUITE_P(Tasks, ExpertKeyframes,
                         ::testing::Values("reach_target", "pick_and_lift", "lift_numbered_block", "reach_prism",
                                           "pick_and_lift_small", "stack_blocks", "setup_checkers"));

namespace {

// One expert demonstration of `task` (seed 4), every record, at `pixels` square.
std::vector<stream::Record> one_demonstration(const std::string& task, int pixels) {
  demos::DemoOptions options;
  options.episodes = {task, 0, 1, 4};
  options.simulator.cameras[0].intrinsics.width = options.simulator.cameras[0].intrinsics.height = pixels;
  std::vector<stream::Record> records;
  demos::record_demos(robot::RobotModel::xarm7(), options, [&](const stream::Record& r) { records.push_back(r); },
                      [](const std::string&) {});
  return records;
}

}  // namespace

TEST(Transitions, ChainsRewardsAndReferencesToStoredFrames) {
  std::vector<stream::Record> out;
  TransitionOptions transition_options;
  EpisodeConverter converter(transition_options);
  const stream::Emit keep = [&](const stream::Record& r) { out.push_back(r); };
  for (const auto& r : one_demonstration("pick_and_lift", 32)) converter.handle(r, keep);
  converter.finish(keep);
  ASSERT_EQ(converter.counts().converted, 1);
  std::set<int> frames;
  int from_start = 0, rewarded = 0;
  for (const auto& r : out) {
    if (r.type() == "frame") {
      frames.insert(r.scalar<int32_t>("frame"));
      EXPECT_TRUE(r.has("front.depth_mm"));
      EXPECT_FALSE(r.has("front.points"));
      continue;
    }
    ASSERT_EQ(r.type(), "transition");
    EXPECT_TRUE(frames.count(r.scalar<int32_t>("frame"))) << "transition before its frame";
    EXPECT_TRUE(frames.count(r.scalar<int32_t>("next_frame")));
    from_start += r.scalar<int32_t>("frame") == 0;
    if (r.scalar<uint8_t>("terminal")) {
      EXPECT_EQ(r.scalar<float>("reward"), 100.0f);
      ++rewarded;
    } else {
      EXPECT_EQ(r.scalar<float>("reward"), 0.0f);
    }
    // The target lies in the (crop-augmented) depth-1 grid, at the stored index.
    const auto pose = r.array<double>("target_pose");
    const auto b = r.array<double>("depth1.bounds");
    voxels::GridBounds deeper{{b[0], b[1], b[2]}, b[3], 16};
    const auto index = r.array<int32_t>("depth1.index");
    EXPECT_EQ(deeper.index_of({pose[0], pose[1], pose[2]}), Eigen::Vector3i(index[0], index[1], index[2]));
  }
  EXPECT_EQ(from_start, 1);            // one chain from frame 0, whose first transition starts there
  EXPECT_GT(rewarded, 1);              // demo augmentation: several chains, each ending rewarded
  EXPECT_EQ(converter.counts().transitions, static_cast<int64_t>(out.size() - frames.size()));
}

namespace {

// A synthetic demonstration: n obs records moving along x, the gripper closing at `close_at`.
std::vector<stream::Record> synthetic_demo(int n, int close_at, double x0 = 0.1) {
  std::vector<stream::Record> demo;
  for (int i = 0; i < n; ++i) {
    stream::Record obs("obs");
    obs.set_scalar<int32_t>("frame", i);
    obs.set_scalar<uint8_t>("gripper_open", i < close_at);
    obs.set<double>("joint_velocities", {7}, std::vector<double>(7, i == n - 1 ? 0.0 : 0.5));
    obs.set<double>("gripper_pose", {7}, std::vector<double>{x0 + 0.01 * i, 0.0, 0.9, 1, 0, 0, 0});
    obs.set_scalar<uint8_t>("success", i == n - 1);
    obs.set_string("task", "synthetic");
    demo.push_back(obs);
  }
  return demo;
}

}  // namespace

TEST(Transitions, BadEpisodesAreSkippedAndCounted) {
  auto good = synthetic_demo(12, 6);
  auto empty = std::vector<stream::Record>{};
  auto single = synthetic_demo(1, 5);
  auto out_of_order = synthetic_demo(12, 6);
  std::swap(out_of_order[3], out_of_order[4]);
  auto outside = synthetic_demo(12, 6, /*x0=*/0.95);  // x beyond the scene's 0.7
  auto failed = synthetic_demo(12, 6);
  failed.back().set_scalar<uint8_t>("success", 0);
  // Each episode ends with an 'episode' record without a success field: use the last obs's.
  std::vector<stream::Record> out;
  EpisodeConverter converter(TransitionOptions{});
  const stream::Emit keep = [&](const stream::Record& r) { out.push_back(r); };
  for (const auto* episode : {&good, &empty, &single, &out_of_order, &outside, &failed}) {
    for (const auto& r : *episode) converter.handle(r, keep);
    stream::Record end("episode");
    end.set_scalar<uint8_t>("success", episode->empty() ? 0 : episode->back().scalar<uint8_t>("success"));
    converter.handle(end, keep);
  }
  const ConversionCounts& c = converter.counts();
  EXPECT_EQ(c.episodes, 6);
  EXPECT_EQ(c.converted, 1);
  EXPECT_EQ(c.skipped_empty, 2);  // no frames, one frame
  EXPECT_EQ(c.skipped_out_of_order, 1);
  EXPECT_EQ(c.skipped_outside_bounds, 1);
  EXPECT_EQ(c.skipped_failed, 1);
  EXPECT_NE(c.summary().find("skipped 1 with frames out of order"), std::string::npos);
  // The good one: keyframes at the gripper change (6) and the last frame (11); one chain from
  // frame 0 and one from frame 10 (demo augmentation): 2 + 1 transitions.
  EXPECT_EQ(c.transitions, 3);
}

// A zero or NaN quaternion in a demonstration is refused naming the record, not binned as
// some rotation.
TEST(Transitions, AGripperPoseWithoutARotationIsRefused) {
  const std::vector<stream::Record> demo = one_demonstration("reach_target", 16);
  for (const std::vector<double>& quaternion : {std::vector<double>{0, 0, 0, 0}, std::vector<double>{NAN, 0, 0, 1}}) {
    std::vector<stream::Record> damaged = demo;
    for (auto& r : damaged)
      if (r.type() == "obs") {
        const auto p = r.array<double>("gripper_pose");
        r.set<double>("gripper_pose", {7}, std::vector<double>{p[0], p[1], p[2], quaternion[0], quaternion[1],
                                                               quaternion[2], quaternion[3]});
      }
    EpisodeConverter converter(TransitionOptions{});
    const stream::Emit drop = [](const stream::Record&) {};
    try {
      for (const auto& r : damaged) converter.handle(r, drop);
      converter.finish(drop);
      ADD_FAILURE() << "converted an episode without rotations";
    } catch (const StreamError& e) {
      EXPECT_NE(std::string(e.what()).find("field 'gripper_pose'"), std::string::npos) << e.what();
    }
  }
}

// The step each transition carries (its time input), both ways, against a count made here: with
// `episode` a transition from frame f is at the step of the keyframes at or before f (where an
// agent acting in that phase is), on every chain alike; with `reset` each chain starts at 0.
TEST(Transitions, ChainStepsCountFromZeroOrFromTheKeyframesPassed) {
  auto demo = synthetic_demo(35, 12);
  demo[22].set<double>("joint_velocities", {7}, std::vector<double>(7, 0.05));  // a stop: keyframe 22
  for (const ChainSteps chain_steps : {ChainSteps::reset, ChainSteps::episode}) {
    TransitionOptions options;
    options.chain_steps = chain_steps;
    EpisodeConverter converter(options);
    std::vector<stream::Record> transitions;
    const stream::Emit keep = [&](const stream::Record& r) {
      if (r.type() == "transition") transitions.push_back(r);
    };
    for (const auto& r : demo) converter.handle(r, keep);
    converter.finish(keep);
    std::set<int> keyframes;
    for (const auto& t : transitions) keyframes.insert(t.scalar<int32_t>("next_frame"));
    ASSERT_EQ(keyframes, (std::set<int>{12, 22, 34}));
    ASSERT_EQ(transitions.size(), 3u + 3u + 2u + 1u);  // chains from frames 0, 10, 20 and 30
    std::set<int> chain_starts_at_zero;
    for (std::size_t i = 0; i < transitions.size(); ++i) {
      const int from = transitions[i].scalar<int32_t>("frame"), step = transitions[i].scalar<int32_t>("step");
      const bool chain_start = !keyframes.count(from);
      int passed = 0;
      for (int k : keyframes) passed += k <= from;
      if (chain_steps == ChainSteps::episode) {
        EXPECT_EQ(step, passed) << "transition from frame " << from;
      } else if (chain_start) {
        EXPECT_EQ(step, 0) << "chain from frame " << from;
        chain_starts_at_zero.insert(from);
      } else {
        EXPECT_EQ(step, transitions[i - 1].scalar<int32_t>("step") + 1);
      }
    }
    if (chain_steps == ChainSteps::reset) EXPECT_EQ(chain_starts_at_zero, (std::set<int>{0, 10, 20, 30}));
  }
}

// Crop augmentation shifts depth d's grid by up to 0.75 of its half edge, and a keyframe lies up
// to half of depth d-1's voxel from that voxel's centre: offsets too small for both are refused
// (the keyframe would be clamped onto the grid's face), the published ones pass.
TEST(Transitions, OffsetsTooSmallForCropAugmentationAreRefused) {
  const auto converter_with = [](std::vector<double> offsets, bool crop) {
    TransitionOptions options;
    options.hierarchy.depths = static_cast<int>(offsets.size()) + 1;
    options.hierarchy.offsets_m = offsets;
    options.crop_augmentation = crop;
    EpisodeConverter converter(options);
  };
  EXPECT_NO_THROW(converter_with({0.15}, true));        // 3.125 cm + 11.25 cm <= 15 cm
  EXPECT_NO_THROW(converter_with({0.15, 0.05}, true));  // and 0.94 cm + 3.75 cm <= 5 cm at depth 2
  EXPECT_NO_THROW(converter_with({0.05}, false));
  EXPECT_NO_THROW(converter_with({0.125}, true));       // 3.125 + 9.375 = 12.5: just inside
  try {
    converter_with({0.05}, true);  // 3.125 cm + 3.75 cm > 5 cm
    FAIL() << "a 5 cm half edge at depth 1 was accepted with crop augmentation";
  } catch (const UsageError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("depth 1's half edge 0.05 m"), std::string::npos) << what;
    EXPECT_NE(what.find("at least 0.125 m or --no-crop-augmentation"), std::string::npos) << what;
  }
  EXPECT_THROW(converter_with({0.15, 0.03}, true), UsageError);  // depth 2: 0.94 + 2.25 > 3 cm
}

// The planner on real scenes: IK accuracy, limits, collision-free paths checked in Bullet,
// failures reported quickly, determinism.
#include <gtest/gtest.h>

#include <chrono>
#include <random>

#include "planning/motion_planner.hpp"
#include "planning/time_parametrization.hpp"
#include "sim_step/simulator.hpp"
#include "test_support.hpp"

using namespace qte;
using namespace qte::planning;

namespace {

using test_support::xarm;

struct Scene {
  sim_step::Simulator sim{xarm(), [] {
                             sim_step::SimulatorOptions o;
                             o.render_threads = 1;
                             return o;
                           }()};
  stream::Record obs{"obs"};
  explicit Scene(const std::string& task, int64_t seed) {
    stream::Record reset("reset");
    reset.set_string("task", task);
    reset.set_scalar<int64_t>("seed", seed);
    sim.handle(reset, [&](const stream::Record& r) { obs = r; });
  }
  world::World& world() { return *sim.world(); }
};

Goal pose_goal(const Eigen::Vector3d& p, double yaw = 0) {
  Goal g;
  g.tcp_pose.linear() = (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitX())).toRotationMatrix();
  g.tcp_pose.translation() = p;
  return g;
}

// Replays a trajectory in the Bullet world at the physics rate; the first contact, or "".
std::string first_contact(world::World& world, const PlanResult& plan) {
  for (std::size_t i = 1; i < plan.joint_positions.size(); ++i) {
    const int steps = 8;
    for (int s = 1; s <= steps; ++s) {
      const double t = static_cast<double>(s) / steps;
      world.set_robot_state(plan.joint_positions[i - 1] + t * (plan.joint_positions[i] - plan.joint_positions[i - 1]),
                            world.finger_opening_m());
      std::string c = world.robot_collision();
      if (c.empty()) c = world.robot_object_contact();
      if (!c.empty()) return c;
    }
  }
  return "";
}

}  // namespace

TEST(InverseKinematics, ForwardInverseForwardRoundTrip) {
  const auto& robot = xarm();
  std::mt19937 rng(5);
  int solved = 0;
  const int trials = 200;
  for (int i = 0; i < trials; ++i) {
    robot::JointVector q, start;
    for (int k = 0; k < 7; ++k) {
      const double lo = std::max(robot.lower_limits()[k], -2.5), hi = std::min(robot.upper_limits()[k], 2.5);
      q[k] = std::uniform_real_distribution<>(lo, hi)(rng);
      start[k] = std::clamp(q[k] + std::uniform_real_distribution<>(-0.5, 0.5)(rng), lo, hi);
    }
    const Eigen::Isometry3d target = robot.tcp_pose(q);
    robot::IkOptions options;
    options.seed = i;
    const auto solution = robot::solve_ik(robot, target, start, options);
    if (!solution) continue;
    ++solved;
    const Eigen::Isometry3d reached = robot.tcp_pose(*solution);
    EXPECT_LE(robot::position_error_m(reached, target), 0.001);
    EXPECT_LE(robot::angle_error_rad(reached, target), 0.5 * M_PI / 180);
    for (int k = 0; k < 7; ++k) {
      EXPECT_GE((*solution)[k], robot.lower_limits()[k]);
      EXPECT_LE((*solution)[k], robot.upper_limits()[k]);
    }
  }
  EXPECT_GE(solved, trials * 97 / 100);  // every target is reachable by construction
}

TEST(TimeParametrization, RespectsVelocityAndAccelerationLimits) {
  robot::JointVector a = robot::JointVector::Zero(), b = a, c = a;
  b << 1.0, -0.5, 0.2, 0.8, 0, 0.3, -1.2;
  c << 1.2, 0.2, 0.2, 0.4, 0.5, 0.3, -1.0;
  const robot::JointVector vmax = robot::JointVector::Constant(1.5), amax = robot::JointVector::Constant(8);
  const TimedPath path = time_parametrize({a, b, c}, vmax, amax, 0.05);
  ASSERT_GT(path.time_s.size(), 3u);
  EXPECT_EQ(path.time_s.front(), 0.0);
  EXPECT_TRUE(path.joint_positions.front().isApprox(a));
  EXPECT_TRUE(path.joint_positions.back().isApprox(c));
  for (std::size_t i = 1; i < path.time_s.size(); ++i) {
    const double dt = path.time_s[i] - path.time_s[i - 1];
    ASSERT_GT(dt, 0);
    const robot::JointVector v = (path.joint_positions[i] - path.joint_positions[i - 1]) / dt;
    EXPECT_LE(v.cwiseAbs().maxCoeff(), 1.5 + 1e-9);
  }
}

TEST(MotionPlanner, PathsAreCollisionFreeInTheTrueScene) {
  int planned = 0;
  for (int64_t seed = 0; seed < 4; ++seed) {
    Scene scene("pick_and_lift", seed);
    MotionPlanner planner(xarm(), scene.world().robot_base_pose());
    const StartState start = start_state_from(scene.obs);
    const OccupancyScene occupancy = planner.scene_from(scene.obs, start);
    // Goals just above each block, and beyond it: paths must pass the blocks.
    for (const char* name : {"target", "distractor1", "distractor2"}) {
      const Eigen::Vector3d block = scene.world().object_pose(scene.world().object_id(name)).translation();
      for (const Eigen::Vector3d& offset : {Eigen::Vector3d(0, 0, 0.09), Eigen::Vector3d(0.0, 0.12, 0.05)}) {
        const PlanResult plan = planner.plan(start, pose_goal(block + offset), occupancy, planned);
        if (!plan.failure.empty()) continue;  // e.g. goal_in_collision next to another block
        ++planned;
        scene.world().set_robot_state(start.joints, start.opening_m);
        EXPECT_EQ(first_contact(scene.world(), plan), "") << name << " seed " << seed << " via " << plan.method;
        for (const auto& q : plan.joint_positions)
          for (int k = 0; k < 7; ++k) {
            EXPECT_GE(q[k], xarm().lower_limits()[k]);
            EXPECT_LE(q[k], xarm().upper_limits()[k]);
          }
        const Eigen::Isometry3d reached = scene.world().robot_base_pose() * xarm().tcp_pose(plan.joint_positions.back());
        EXPECT_LE((reached.translation() - (block + offset)).norm(), 0.001);
      }
    }
  }
  EXPECT_GE(planned, 16);
}

TEST(MotionPlanner, UnreachableAndInvalidGoalsFailFast) {
  Scene scene("reach_target", 1);
  MotionPlanner planner(xarm(), scene.world().robot_base_pose());
  const StartState start = start_state_from(scene.obs);
  const OccupancyScene occupancy = planner.scene_from(scene.obs, start);
  auto timed = [&](const Goal& goal) {
    const auto t0 = std::chrono::steady_clock::now();
    const PlanResult r = planner.plan(start, goal, occupancy);
    EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 1.0);
    return r.failure;
  };
  EXPECT_EQ(timed(pose_goal({2.0, 0, 1.0})), "outside_workspace");
  // Within 0.95 m of the shoulder but not with the gripper pointing down: the flange would
  // have to be 1.07 m above the shoulder.
  EXPECT_EQ(timed(pose_goal({-0.3, 0.0, 0.752 + 0.267 + 0.9})), "ik_failed");
  Goal nan = pose_goal({0.1, 0, 1.0});
  nan.pose_valid = false;
  EXPECT_EQ(timed(nan), "invalid_pose");
  // A goal inside the table.
  EXPECT_EQ(timed(pose_goal({0.1, 0.0, 0.74})), "goal_in_collision");
}

TEST(MotionPlanner, ActionRecordsAreValidated) {
  stream::Record action("action");
  action.set<double>("pose", {7}, std::vector<double>{0.1, 0, 1, 0, 0, 0, 0.5});  // |q| = 0.5
  EXPECT_FALSE(goal_from(action).pose_valid);
  action.set<double>("pose", {7}, std::vector<double>{0.1, NAN, 1, 1, 0, 0, 0});
  EXPECT_FALSE(goal_from(action).pose_valid);
  action.set<double>("pose", {7}, std::vector<double>{0.1, 0, 1, 1, 0, 0, 0});
  EXPECT_TRUE(goal_from(action).pose_valid);
  EXPECT_THROW(goal_from(stream::Record("action")), StreamError);
  stream::Record obs("obs");
  obs.set<double>("joint_positions", {7}, std::vector<double>(7, 0.0));
  obs.set_scalar<double>("gripper_opening_m", 0.085);
  obs.set_scalar<uint8_t>("gripper_open", 1);
  MotionPlanner planner(xarm(), world::SceneLayout{}.robot_base_pose());
  EXPECT_THROW(planner.scene_from(obs, start_state_from(obs)), StreamError);  // no point cloud

  // A camera pose with a NaN: an error naming the field, not a scene seen from nowhere.
  Scene scene("reach_target", 1);
  std::vector<double> extrinsics(scene.obs.array<double>("front.extrinsics").begin(),
                                 scene.obs.array<double>("front.extrinsics").end());
  extrinsics[7] = NAN;
  scene.obs.set<double>("front.extrinsics", {4, 4}, extrinsics);
  try {
    planner.scene_from(scene.obs, start_state_from(scene.obs));
    FAIL() << "NaN extrinsics accepted";
  } catch (const StreamError& e) {
    EXPECT_NE(std::string(e.what()).find("front.extrinsics"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("finite"), std::string::npos) << e.what();
  }
}

TEST(MotionPlanner, SameSeedSamePlan) {
  Scene scene("pick_and_lift", 2);
  const StartState start = start_state_from(scene.obs);
  auto plan = [&](uint64_t seed) {
    PlannerOptions options;
    options.seed = seed;
    MotionPlanner planner(xarm(), scene.world().robot_base_pose(), options);
    const OccupancyScene occupancy = planner.scene_from(scene.obs, start);
    const Eigen::Vector3d block = scene.world().object_pose(scene.world().object_id("distractor2")).translation();
    return planner.plan(start, pose_goal(block + Eigen::Vector3d(0, 0.1, 0.05), 0.4), occupancy, 3);
  };
  const PlanResult a = plan(9), b = plan(9);
  ASSERT_EQ(a.failure, b.failure);
  ASSERT_EQ(a.joint_positions.size(), b.joint_positions.size());
  for (std::size_t i = 0; i < a.joint_positions.size(); ++i) EXPECT_EQ(a.joint_positions[i], b.joint_positions[i]);
  EXPECT_EQ(a.time_s, b.time_s);
}

TEST(MotionPlanner, IgnoreCollisionsMovesInAStraightLine) {
  Scene scene("pick_and_lift", 3);
  MotionPlanner planner(xarm(), scene.world().robot_base_pose());
  const StartState start = start_state_from(scene.obs);
  const OccupancyScene occupancy = planner.scene_from(scene.obs, start);
  const Eigen::Isometry3d from = scene.world().tcp_pose();
  Goal goal = pose_goal(from.translation() + Eigen::Vector3d(0.1, 0.05, -0.1));
  goal.tcp_pose.linear() = from.linear();
  goal.ignore_collisions = true;
  const PlanResult plan = planner.plan(start, goal, occupancy);
  ASSERT_EQ(plan.failure, "");
  EXPECT_EQ(plan.method, "straight_line");
  const Eigen::Vector3d a = from.translation(), b = goal.tcp_pose.translation();
  for (const auto& q : plan.joint_positions) {  // every sample on the segment a-b
    const Eigen::Vector3d p = (scene.world().robot_base_pose() * xarm().tcp_pose(q)).translation();
    const double t = std::clamp((p - a).dot(b - a) / (b - a).squaredNorm(), 0.0, 1.0);
    EXPECT_LT((a + t * (b - a) - p).norm(), 0.002);
  }
}

// A grasp commanded straight from the start pose, as a learning agent does before it has
// learned the pose above the object: with the space around the goal left out of the map, the
// path may sweep through the cup it goes for; with --approach it is planned to the pose 10 cm
// back along the tool axis on the whole map and ends in a straight descent, as the expert's.
TEST(MotionPlanner, GraspsApproachAlongTheToolAxis) {
  int swept = 0, approached = 0;
  for (int64_t seed = 0; seed < 6; ++seed) {
    Scene scene("pick_up_cup", seed);
    const int cup = scene.world().object_id("cup");
    const world::ObjectSpec& spec = scene.world().object_spec(cup);
    const Eigen::Vector3d centre = scene.world().object_pose(cup) * spec.grasp_region.center();
    Goal grasp = pose_goal(centre);
    grasp.gripper_open = false;
    const StartState start = start_state_from(scene.obs);
    for (const double approach : {0.0, 0.1}) {
      PlannerOptions options;
      options.approach_m = approach;
      MotionPlanner planner(xarm(), scene.world().robot_base_pose(), options);
      ASSERT_EQ(planner.approaches(start, grasp), approach > 0);
      const OccupancyScene occupancy = planner.scene_from(scene.obs, start, &grasp);
      const PlanResult plan = planner.plan(start, grasp, occupancy, static_cast<uint64_t>(seed));
      ASSERT_EQ(plan.failure, "") << "seed " << seed << " approach " << approach;
      scene.world().set_robot_state(start.joints, start.opening_m);
      const std::string contact = first_contact(scene.world(), plan);
      if (approach == 0) {
        swept += !contact.empty();
        continue;
      }
      ++approached;
      EXPECT_NE(plan.method.find("+approach"), std::string::npos) << plan.method;
      EXPECT_EQ(contact, "") << "seed " << seed << " via " << plan.method;
      // The path's last samples, back to the pose 10 cm up the tool axis, lie on that axis.
      const Eigen::Vector3d axis = grasp.tcp_pose.linear().col(2);
      double farthest = 0;
      for (auto q = plan.joint_positions.rbegin(); q != plan.joint_positions.rend(); ++q) {
        const Eigen::Vector3d d = (scene.world().robot_base_pose() * xarm().tcp_pose(*q)).translation() - centre;
        if (d.norm() > 0.1005) break;
        farthest = std::max(farthest, d.norm());
        EXPECT_LT((d - d.dot(axis) * axis).norm(), 0.002) << "seed " << seed;
        EXPECT_LE(d.dot(axis), 1e-3);  // behind the goal, never past it
      }
      EXPECT_GT(farthest, 0.099) << "seed " << seed << ": the straight approach starts 10 cm back";
      const Eigen::Isometry3d reached = scene.world().robot_base_pose() * xarm().tcp_pose(plan.joint_positions.back());
      EXPECT_LE((reached.translation() - centre).norm(), 0.001);
    }
  }
  EXPECT_EQ(approached, 6);
  // These scenes show the fault the option is for: were the default planner to stop sweeping
  // through the cup, they would no longer test the approach.
  EXPECT_GE(swept, 3) << "too few paths to a grasp planned with the goal's surroundings free touched the cup";
}

// Only a grasp gets the approach: a move closing an open, empty gripper, not flagged
// ignore_collisions, with --approach set.
TEST(MotionPlanner, OnlyGraspsApproach) {
  PlannerOptions options;
  options.approach_m = 0.1;
  const MotionPlanner planner(xarm(), world::SceneLayout{}.robot_base_pose(), options);
  const MotionPlanner without(xarm(), world::SceneLayout{}.robot_base_pose());
  StartState open;
  open.opening_m = 0.085;
  Goal grasp = pose_goal({0.3, 0, 0.8});
  grasp.gripper_open = false;
  EXPECT_TRUE(planner.approaches(open, grasp));
  EXPECT_FALSE(without.approaches(open, grasp));
  StartState holding = open;
  holding.holding = true;  // placing a held object
  EXPECT_FALSE(planner.approaches(holding, grasp));
  StartState closed = open;
  closed.opening_m = 0.005;  // closed on nothing: nothing to enclose
  EXPECT_FALSE(planner.approaches(closed, grasp));
  Goal move = grasp;
  move.gripper_open = true;  // the gripper stays open: not a grasp
  EXPECT_FALSE(planner.approaches(open, move));
  Goal straight = grasp;
  straight.ignore_collisions = true;  // already a straight line
  EXPECT_FALSE(planner.approaches(open, straight));
}

// Test helpers: joint-space straight-line trajectories to IK solutions (plan-path does this
// properly, with collision checking; these tests need only a way to move the arm).
#pragma once

#include <gtest/gtest.h>

#include "robot/inverse_kinematics.hpp"
#include "sim_step/simulator.hpp"

namespace qte::test_support {

inline stream::Record straight_trajectory(const robot::RobotModel& robot, const robot::JointVector& from,
                                          const robot::JointVector& to, bool gripper_open) {
  const double speed = 0.5 * robot.max_velocities().minCoeff();
  const double duration = std::max(0.1, (to - from).cwiseAbs().maxCoeff() / speed);
  const int n = 2;
  std::vector<double> times = {0, duration}, joints;
  for (const auto* q : {&from, &to})
    for (int k = 0; k < 7; ++k) joints.push_back((*q)[k]);
  stream::Record t("trajectory");
  t.set<double>("time_s", {n}, times);
  t.set<double>("joint_positions", {n, 7}, joints);
  t.set_scalar<uint8_t>("gripper_open", gripper_open);
  return t;
}

// IK for a world-frame TCP pose from the world's current joint positions.
inline robot::JointVector ik_world(const world::World& world, const Eigen::Isometry3d& tcp_in_world) {
  const auto q = robot::solve_ik(world.robot(), world.robot_base_pose().inverse() * tcp_in_world,
                                 world.joint_positions());
  EXPECT_TRUE(q.has_value()) << "no IK solution for " << tcp_in_world.translation().transpose();
  return q.value_or(world.joint_positions());
}

}  // namespace qte::test_support

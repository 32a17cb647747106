// Shared by the task tests: a task's scene built from a seed and a variation, object poses by
// name, and placing an object by hand (teleported arm, real grasp, release and physics) as the
// experts' place waypoints do it, without the planner.
#pragma once

#include <gtest/gtest.h>

#include <memory>
#include <random>
#include <string>

#include "sim_step/trajectory_helpers.hpp"
#include "tasks/blocks.hpp"
#include "tasks/task.hpp"
#include "test_support.hpp"

namespace qte::test_support {

struct TaskScene {
  world::World world{xarm()};
  std::unique_ptr<tasks::Task> task;
  TaskScene(const std::string& name, uint64_t seed, int variation) : task(tasks::make_task(name)) {
    std::mt19937_64 rng(seed);
    task->build(world, variation, rng);
  }
  Eigen::Isometry3d pose(const std::string& name) const { return world.object_pose(world.object_id(name)); }

  // Grasps `name` from above at its grasp point (TCP x along world yaw `grasp_yaw`, the
  // fingers closing across it), carries it until its origin is at `to` + 5 mm with TCP yaw
  // `place_yaw` (the grasp point's offset from the origin kept as it was), and unless told
  // not to opens, lets physics settle it for 0.5 s and moves the open gripper 10 cm up.
  void place(const std::string& name, double grasp_yaw, const Eigen::Vector3d& to, double place_yaw,
             bool release = true) {
    const Eigen::Vector3d offset = grasp(name, grasp_yaw) - pose(name).translation();
    if (world.held_object() != world.object_id(name)) return;  // the failed grasp is reported
    Eigen::Isometry3d tcp = Eigen::Isometry3d::Identity();
    tcp.linear() = tasks::top_down(place_yaw);
    tcp.translation() = to + offset + Eigen::Vector3d(0, 0, 0.005);
    world.set_robot_state(ik_world(world, tcp), world.finger_opening_m());
    if (!release) return;
    world.open_gripper();
    world.settle(0.5);
    tcp.translation().z() += 0.1;
    world.set_robot_state(ik_world(world, tcp), 0.085);
  }

  // The open gripper teleported to `name`'s grasp point (TCP yaw `yaw`) and closed on it;
  // returns the grasp point.
  Eigen::Vector3d grasp(const std::string& name, double yaw) {
    const Eigen::Vector3d at = tasks::grasp_point(world, world.object_id(name));
    Eigen::Isometry3d tcp = Eigen::Isometry3d::Identity();
    tcp.linear() = tasks::top_down(yaw);
    tcp.translation() = at;
    world.set_robot_state(ik_world(world, tcp), 0.085);
    EXPECT_EQ(world.close_gripper(), world.object_id(name)) << name;
    return at;
  }

  // The gripper (and what it holds) moved straight up by `dz` metres.
  void lift(double dz) {
    Eigen::Isometry3d tcp = world.tcp_pose();
    tcp.translation().z() += dz;
    world.set_robot_state(ik_world(world, tcp), world.finger_opening_m());
  }
};

}  // namespace qte::test_support

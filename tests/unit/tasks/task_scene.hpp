// Shared by the task tests: a task's scene built from a seed and a variation, object poses by
// name, and placing an object by hand (teleported arm, real grasp, release and physics) as the
// experts' place waypoints do it, without the planner.
#pragma once

#include <gtest/gtest.h>

#include <memory>
#include <random>
#include <string>

#include "sim_step/trajectory_helpers.hpp"
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

  // Grasps `name` from above with the fingers closing along world yaw `grasp_yaw`, carries it
  // to `to` + 5 mm (its centre) with yaw `place_yaw`, and unless told not to opens, lets
  // physics settle it for 0.5 s and moves the open gripper 10 cm up.
  void place(const std::string& name, double grasp_yaw, const Eigen::Vector3d& to, double place_yaw,
             bool release = true) {
    Eigen::Isometry3d tcp = Eigen::Isometry3d::Identity();
    tcp.linear() = tasks::top_down(grasp_yaw);
    tcp.translation() = pose(name).translation();
    world.set_robot_state(ik_world(world, tcp), 0.085);
    ASSERT_EQ(world.close_gripper(), world.object_id(name)) << name;
    tcp.linear() = tasks::top_down(place_yaw);
    tcp.translation() = to + Eigen::Vector3d(0, 0, 0.005);
    world.set_robot_state(ik_world(world, tcp), world.finger_opening_m());
    if (!release) return;
    world.open_gripper();
    world.settle(0.5);
    tcp.translation().z() += 0.1;
    world.set_robot_state(ik_world(world, tcp), 0.085);
  }
};

}  // namespace qte::test_support

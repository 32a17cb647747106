// Blocks on the table and the top-down grasp of one, shared by the block tasks.
#pragma once

#include "tasks/catalogue.hpp"

namespace qte::tasks {

constexpr double kBlockSize = 0.05;

// A block resting on the table at (x, y) with yaw `yaw_rad`.
sim::ObjectSpec block(const sim::World& world, const std::string& name, const Eigen::Vector3d& xy,
                      double yaw_rad, const Eigen::Vector3f& colour);

// Pre-grasp above the block, grasp at its centre (gripper closes), then lift straight up by
// `lift_m`: the first three waypoints of every pick task.
std::vector<Waypoint> grasp_and_lift(const sim::World& world, int block_id, double lift_m);

}  // namespace qte::tasks

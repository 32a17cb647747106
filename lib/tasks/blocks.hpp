// Blocks on the table, the top-down grasp of an object and the success zone it is lifted into:
// what the pick tasks share.
#pragma once

#include "tasks/catalogue.hpp"

namespace qte::tasks {

constexpr double kBlockSize = 0.05;

// A block resting on the table at (x, y) with yaw `yaw_rad`.
world::ObjectSpec block(const world::World& world, const std::string& name, const Eigen::Vector3d& xy,
                      double yaw_rad, const Eigen::Vector3f& colour);

// Pre-grasp 10 cm above `centre`, grasp there (gripper closes; TCP x along world yaw
// `yaw_rad`, so the fingers close across it), then lift straight up by `lift_m`: the first
// three waypoints of every pick task.
std::vector<Waypoint> grasp_at(const Eigen::Vector3d& centre, double yaw_rad, double lift_m);
// grasp_at the block's centre, square to its faces.
std::vector<Waypoint> grasp_and_lift(const world::World& world, int block_id, double lift_m);
// The yaw of a pose's x axis about world z.
double yaw_of(const Eigen::Isometry3d& pose);
// Where the fingers close on an object (world frame): its grasp region's centre, or its origin.
Eigen::Vector3d grasp_point(const world::World& world, int object_id);

// Placing the held object: over `resting_centre` (where its centre will rest) by `above_m`,
// down to 5 mm over it, the gripper opening there (released; physics settles it), back up;
// the fingers closing along world yaw `yaw_rad`.
std::vector<Waypoint> place_at(const Eigen::Vector3d& resting_centre, double yaw_rad, double above_m);

// The green sphere an object is lifted into, 0.3 m above the table at (x, y); seen, not felt.
world::ObjectSpec success_zone(const world::World& world, const Eigen::Vector3d& xy, double radius);
// grasp_and_lift by 15 cm, then into the scene's "success_zone".
std::vector<Waypoint> lift_into_zone(const world::World& world, int object_id);
// The object is held and its centre inside the scene's "success_zone" of `radius`.
bool held_in_zone(const world::World& world, int object_id, double radius);

}  // namespace qte::tasks

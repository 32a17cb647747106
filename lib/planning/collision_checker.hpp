// The planner's validity checker, as OMPL separates it from the planner: is the arm free at a
// joint configuration, and along a straight joint-space motion between two? Free means no
// self-collision of the robot's spheres, no sphere below the table top but the base's (the
// cameras see only the top; below it is solid, not free) and, given a sensed scene, none
// within the clearance of its occupied voxels.
#pragma once

#include <Eigen/Geometry>

#include "planning/occupancy_scene.hpp"
#include "planning/robot_spheres.hpp"
#include "robot/robot_model.hpp"
#include "world/scene_layout.hpp"

namespace qte::planning {

// The spheres over-cover the links, so a sphere may reach this far into the table top (or out of
// a workspace box) while its link does not: grasps of low objects bring the finger spheres there.
constexpr double kSphereOvercover_m = 0.005;

struct CollisionCheckOptions {
  double clearance_m = 0.0;      // extra distance kept from occupied voxels
  double check_step_rad = 0.02;  // motions are checked at least every this much of any joint
  double table_height_m = world::SceneLayout::kTableHeight_m;
};

class CollisionChecker {
 public:
  CollisionChecker(const RobotSpheres& spheres, const Eigen::Isometry3d& world_from_base, CollisionCheckOptions options);

  // `scene` null: the robot and the table only (moves that ignore the sensed scene).
  bool state_valid(const robot::JointVector& q, double opening_m, const OccupancyScene* scene) const;
  // Every configuration along the straight joint-space line from `a` to `b`, at check_step_rad.
  bool motion_valid(const robot::JointVector& a, const robot::JointVector& b, double opening_m,
                    const OccupancyScene* scene) const;

 private:
  const RobotSpheres& spheres_;
  Eigen::Isometry3d world_from_base_;
  CollisionCheckOptions options_;
};

}  // namespace qte::planning

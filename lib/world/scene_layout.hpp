// The layout every task's scene shares: the table and the robot base on it (DESIGN §4-§5).
// Eigen only, so that the planner and tools can take its figures without the Bullet world.
#pragma once

#include <Eigen/Geometry>

namespace qte::world {

// What the table and the robot base look like; tasks share one layout (DESIGN §4-§5).
struct SceneLayout {
  static constexpr double kTableHeight_m = 0.752;  // the table top's height above the floor
  double table_height_m = kTableHeight_m;
  Eigen::Vector3d table_centre{0.2, 0.0, kTableHeight_m};  // top surface centre
  Eigen::Vector2d table_extent_m{1.2, 1.4};
  Eigen::Vector3d robot_base{-0.3, 0.0, kTableHeight_m};

  // The arm's joints (rad) at the start of every episode: the gripper above the table,
  // pointing down (the fingers open).
  static Eigen::Matrix<double, 7, 1> ready_joints() {
    Eigen::Matrix<double, 7, 1> q;
    q << 0, -0.35, 0, 0.75, 0, 1.1, 0;
    return q;
  }

  Eigen::Isometry3d robot_base_pose() const {  // facing +x, on the table
    Eigen::Isometry3d base = Eigen::Isometry3d::Identity();
    base.translation() = robot_base;
    return base;
  }
};

}  // namespace qte::world

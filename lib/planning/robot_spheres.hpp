// The robot as spheres, for fast collision queries against a distance field and for
// self-collision: every primitive of every link (lib/robot) covered by a few spheres.
#pragma once

#include <Eigen/Geometry>
#include <vector>

#include "robot/robot_model.hpp"

namespace qte::planning {

struct Sphere {
  Eigen::Vector3d centre;  // world frame once placed; link frame in the model
  double radius_m = 0;
  int link = -1;
};

class RobotSpheres {
 public:
  explicit RobotSpheres(const robot::RobotModel& robot);

  // The spheres in the world frame for joint positions q, finger opening, and the robot's
  // base pose in the world. `out` is resized.
  void place(const robot::JointVector& q, double opening_m, const Eigen::Isometry3d& world_from_base,
             std::vector<Sphere>& out) const;

  // True when two links that may not touch (robot::RobotModel::self_collision_pairs) overlap,
  // given spheres placed by place(). `margin_m` shrinks the test (spheres over-cover).
  bool self_collision(const std::vector<Sphere>& placed, double margin_m = 0.0) const;

  const std::vector<Sphere>& model() const { return spheres_; }  // in link frames

 private:
  std::vector<Sphere> spheres_;
  std::vector<std::pair<int, int>> checked_pairs_;  // sphere index pairs of the checked link pairs
  std::vector<std::vector<int>> link_spheres_;     // sphere indices per link
  const robot::RobotModel& robot_;
};

}  // namespace qte::planning

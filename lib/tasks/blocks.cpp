#include "tasks/blocks.hpp"

#include <cmath>

namespace qte::tasks {

sim::ObjectSpec block(const sim::World& world, const std::string& name, const Eigen::Vector3d& xy,
                      double yaw_rad, const Eigen::Vector3f& colour) {
  sim::ObjectSpec spec;
  spec.name = name;
  spec.shape = sim::ObjectSpec::Shape::box;
  spec.size = Eigen::Vector3d::Constant(kBlockSize);
  spec.pose.linear() = Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  spec.pose.translation() << xy.x(), xy.y(), world.layout().table_height_m + kBlockSize / 2;
  spec.mass_kg = 0.1;
  spec.appearance.colour = colour;
  return spec;
}

std::vector<Waypoint> grasp_and_lift(const sim::World& world, int block_id, double lift_m) {
  const Eigen::Isometry3d pose = world.object_pose(block_id);
  // Fingers close across two opposite faces: the block's yaw modulo a quarter turn.
  const Eigen::Vector3d x_axis = pose.linear().col(0);
  double yaw = std::atan2(x_axis.y(), x_axis.x());
  yaw = std::remainder(yaw, M_PI / 2);
  Waypoint above, grasp, lift;
  above.tcp_pose.linear() = grasp.tcp_pose.linear() = lift.tcp_pose.linear() = top_down(yaw);
  grasp.tcp_pose.translation() = pose.translation();
  above.tcp_pose.translation() = pose.translation() + Eigen::Vector3d(0, 0, 0.1);
  lift.tcp_pose.translation() = pose.translation() + Eigen::Vector3d(0, 0, lift_m);
  grasp.gripper_open = false;
  grasp.ignore_collisions = true;  // the straight approach touches the block on purpose
  lift.gripper_open = false;
  lift.ignore_collisions = true;
  return {above, grasp, lift};
}

}  // namespace qte::tasks

#include "tasks/blocks.hpp"

#include <cmath>

namespace qte::tasks {

world::ObjectSpec block(const world::World& world, const std::string& name, const Eigen::Vector3d& xy,
                      double yaw_rad, const Eigen::Vector3f& colour) {
  world::ObjectSpec spec;
  spec.name = name;
  spec.shape = world::ObjectSpec::Shape::box;
  spec.size = Eigen::Vector3d::Constant(kBlockSize);
  spec.pose.linear() = Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  spec.pose.translation() << xy.x(), xy.y(), world.layout().table_height_m + kBlockSize / 2;
  spec.mass_kg = 0.1;
  spec.appearance.colour = colour;
  return spec;
}

std::vector<Waypoint> grasp_at(const Eigen::Vector3d& centre, double yaw_rad, double lift_m) {
  Waypoint above, grasp, lift;
  above.tcp_pose.linear() = grasp.tcp_pose.linear() = lift.tcp_pose.linear() = top_down(yaw_rad);
  grasp.tcp_pose.translation() = centre;
  above.tcp_pose.translation() = centre + Eigen::Vector3d(0, 0, 0.1);
  lift.tcp_pose.translation() = centre + Eigen::Vector3d(0, 0, lift_m);
  grasp.gripper_open = false;
  grasp.ignore_collisions = true;  // the straight approach touches the object on purpose
  lift.gripper_open = false;
  lift.ignore_collisions = true;
  return {above, grasp, lift};
}

std::vector<Waypoint> grasp_and_lift(const world::World& world, int block_id, double lift_m) {
  const Eigen::Isometry3d pose = world.object_pose(block_id);
  // Fingers close across two opposite faces: the block's yaw modulo a quarter turn.
  return grasp_at(pose.translation(), std::remainder(yaw_of(pose), M_PI / 2), lift_m);
}

double yaw_of(const Eigen::Isometry3d& pose) { return std::atan2(pose.linear()(1, 0), pose.linear()(0, 0)); }

Eigen::Vector3d grasp_point(const world::World& world, int object_id) {
  const Eigen::AlignedBox3d& region = world.object_spec(object_id).grasp_region;
  const Eigen::Isometry3d pose = world.object_pose(object_id);
  return region.isEmpty() ? pose.translation() : Eigen::Vector3d(pose * region.center());
}

std::vector<Waypoint> place_at(const Eigen::Vector3d& resting_centre, double yaw_rad, double above_m) {
  Waypoint over, place, retreat;
  over.tcp_pose.linear() = place.tcp_pose.linear() = retreat.tcp_pose.linear() = top_down(yaw_rad);
  place.tcp_pose.translation() = resting_centre + Eigen::Vector3d(0, 0, 0.005);
  over.tcp_pose.translation() = retreat.tcp_pose.translation() = place.tcp_pose.translation() + Eigen::Vector3d(0, 0, above_m);
  over.gripper_open = false;
  place.ignore_collisions = retreat.ignore_collisions = true;  // the held object meets what it goes on
  return {over, place, retreat};  // place.gripper_open: opened on arrival
}

world::ObjectSpec success_zone(const world::World& world, const Eigen::Vector3d& xy, double radius) {
  world::ObjectSpec zone;
  zone.name = "success_zone";
  zone.shape = world::ObjectSpec::Shape::sphere;
  zone.size = Eigen::Vector3d(radius, 0, 0);
  zone.pose.translation() << xy.x(), xy.y(), world.layout().table_height_m + 0.3;
  zone.mass_kg = 0;
  zone.collides = false;
  zone.graspable = false;
  zone.appearance.colour = Eigen::Vector3f(0.55f, 0.95f, 0.55f);
  return zone;
}

std::vector<Waypoint> lift_into_zone(const world::World& world, int object_id) {
  auto waypoints = grasp_and_lift(world, object_id, 0.15);
  Waypoint into_zone = waypoints.back();
  into_zone.tcp_pose.translation() = world.object_pose(world.object_id("success_zone")).translation();
  into_zone.ignore_collisions = false;
  waypoints.push_back(into_zone);
  return waypoints;
}

bool held_in_zone(const world::World& world, int object_id, double radius) {
  const Eigen::Vector3d zone = world.object_pose(world.object_id("success_zone")).translation();
  return world.held_object() == object_id && (world.object_pose(object_id).translation() - zone).norm() <= radius;
}

}  // namespace qte::tasks

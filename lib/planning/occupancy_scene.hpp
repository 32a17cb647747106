// The scene as the camera saw it: an OctoMap built from an observation's point clouds (camera
// rays inserted, so free and unknown space are known), with the robot's own links and a held
// object filtered out, and a Euclidean distance field over its occupied voxels for collision
// checks. The rays are traced only when free space is asked about: planning needs the
// occupied voxels alone, and those follow from the endpoints (see occupancy_scene.cpp).
#pragma once

#include <Eigen/Geometry>
#include <memory>
#include <string>
#include <vector>

#include "planning/robot_spheres.hpp"

namespace qte::planning {

struct SceneOptions {
  double resolution_m = 0.01;
  // Box of the world the map covers (the scene bounds plus the arm's reach); points outside
  // are ignored.
  Eigen::Vector3d min_corner{-0.8, -0.8, 0.70};
  Eigen::Vector3d max_corner{0.9, 0.8, 1.8};
  double max_distance_m = 0.2;     // the distance field saturates here
  double robot_filter_margin_m = 0.02;  // points this close to the robot's spheres are its own
  int threads = 1;                 // for the distance transform
};

class OccupancyScene {
 public:
  explicit OccupancyScene(const SceneOptions& options = {});
  ~OccupancyScene();
  OccupancyScene(OccupancyScene&&) noexcept;
  OccupancyScene& operator=(OccupancyScene&&) noexcept;

  // Inserts one camera's world-frame points (count x 3 floats; NaN entries skipped) as rays
  // from `sensor_origin`. Points on the robot (spheres `robot`, placed for the observation's
  // joint state) and inside any of `free_regions` (a held object; the goal of the move, which
  // the agent chose, so reach targets and success zones are not obstacles) are dropped first.
  void insert_camera(const float* points_xyz, std::size_t count, const Eigen::Vector3d& sensor_origin,
                     const std::vector<Sphere>& robot, const std::vector<Sphere>& free_regions);
  // Call once after all insertions, before distance queries.
  void build_distance_field();

  // Distance from `p` to the nearest occupied voxel centre, saturated at max_distance_m;
  // unknown space, and anywhere outside the box, counts as free. Measured from the centre of
  // the voxel holding `p`, so it may be off by up to sqrt(3)/2 resolution. Throws Error
  // before build_distance_field() (or after a later insert_camera).
  double distance_m(const Eigen::Vector3d& p) const;
  // True when some sphere is closer to an occupied voxel than its radius plus `clearance_m`.
  bool collides(const std::vector<Sphere>& spheres, double clearance_m = 0.0) const;

  // What the map knows about the point: never observed, observed free, or occupied.
  enum class Occupancy { unknown, free, occupied };
  Occupancy occupancy_at(const Eigen::Vector3d& p) const;

  // Occupied voxels of the traced map at its resolution (pruned nodes count for all they cover).
  std::size_t occupied_voxels() const;
  // Their centres, world frame: for tests and visualisation.
  std::vector<Eigen::Vector3d> occupied_voxel_centres() const;
  // OctoMap's binary format (.bt), opens in octovis.
  void write_binary(const std::string& path) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace qte::planning

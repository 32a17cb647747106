// A task: the objects of a scene and how they are randomised (from a seed and a variation),
// when it is solved, and a scripted expert as next-best poses (RLBench's waypoints).
#pragma once

#include <Eigen/Geometry>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "world/world.hpp"
#include "tasks/episode.hpp"

namespace qte::tasks {

// One next-best pose of the expert: where the TCP goes (world frame), the gripper state
// after arriving, and whether the planner may ignore collisions (straight approach moves).
struct Waypoint {
  Eigen::Isometry3d tcp_pose = Eigen::Isometry3d::Identity();
  bool gripper_open = true;
  bool ignore_collisions = false;
};

class Task {
 public:
  virtual ~Task() = default;
  virtual std::string name() const = 0;
  virtual int variation_count() const = 0;
  // In words, for people and logs, e.g. "lift the block numbered 2".
  virtual std::string description(int variation) const = 0;
  // Adds the task's objects to an empty world, randomised by `rng`, each with its role
  // (ObjectSpec::Role): the objects the variation asks for are targets, their lookalikes
  // and rivals distractors (the other blocks, shapes, cups, tomatoes, the checkers already
  // home), the rest (zones, bins, boards, racks) other.
  virtual void build(world::World& world, int variation, std::mt19937_64& rng) = 0;
  virtual bool success(const world::World& world) const = 0;
  virtual std::vector<Waypoint> expert_waypoints(const world::World& world) const = 0;

  // Next-best poses per episode: the published 10, more where the expert needs more
  // (its keyframes plus slack). The 'obs' records carry it as episode_length.
  virtual int episode_length() const { return kPublishedEpisodeLength; }
};

// The tasks by name; an unknown name is an Error listing the known ones.
std::unique_ptr<Task> make_task(const std::string& name);
std::vector<std::string> task_names();
// The names joined by ", " (for usage texts and errors).
std::string task_list();

// A top-down gripper orientation (TCP z pointing down), TCP x along the world direction at
// angle `yaw_rad` about z; the fingers close along TCP y, across that direction.
Eigen::Matrix3d top_down(double yaw_rad);

}  // namespace qte::tasks

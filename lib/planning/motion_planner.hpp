// From an observation and a next-best pose to a joint trajectory: IK for the goal, a
// collision-free path on the sensed scene (OMPL RRT-Connect in joint space, after trying the
// direct line), deterministic shortcutting, and a time parametrisation within the xArm 7's
// velocity and acceleration limits. Moves flagged ignore-collisions follow a straight line
// of the TCP instead (grasp approaches), as in RLBench and PerAct.
#pragma once

#include <Eigen/Geometry>
#include <chrono>
#include <optional>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "planning/collision_checker.hpp"
#include "planning/occupancy_scene.hpp"
#include "planning/robot_spheres.hpp"
#include "stream/field_names.hpp"
#include "world/scene_layout.hpp"
#include "robot/inverse_kinematics.hpp"
#include "stream/record.hpp"
#include "stream/stage.hpp"

namespace qte::planning {

struct PlannerOptions {
  double time_budget_s = 2.0;          // RRT-Connect stops here with "timeout"
  double velocity_scale = 0.5;         // of the joints' 180 deg/s
  double max_acceleration_rad_s2 = 8;  // per joint
  double sample_period_s = 0.05;       // trajectory samples (sim-step's control period)
  double straight_step_m = 0.01;       // TCP step of straight-line moves
  double goal_free_radius_m = 0.06;    // around the goal TCP, points are not obstacles
  // Grasps (a move that ends closing an open, empty gripper) with approach_m > 0: planned to
  // the pose approach_m back along the TCP's z axis on the whole sensed scene (the object to be
  // grasped an obstacle like any other), then a straight line to the goal checked against the
  // robot and the table, as a grasp approach. 0: planned to the goal itself, around which
  // goal_free_radius_m is free space. The straight approach enters the object on purpose, as
  // an ignore_collisions move does; any move that closes an open gripper counts as a grasp.
  double approach_m = 0;
  CollisionCheckOptions collision;     // clearance, check step, the table (under its top is never free)
  uint64_t seed = 0;
  SceneOptions scene;
};

struct Goal {
  Eigen::Isometry3d tcp_pose = Eigen::Isometry3d::Identity();  // world frame
  bool gripper_open = true;
  bool ignore_collisions = false;
  bool pose_valid = true;  // false for NaNs or a quaternion whose norm is not 1 (+-1e-3)
};

struct PlanResult {
  std::string failure;  // empty on success: ik_failed, start_in_collision, goal_in_collision,
                        // no_path, timeout, invalid_pose, outside_workspace, approach_blocked
                        // (no straight approach to a grasp from any collision-free pose behind it)
  std::vector<double> time_s;
  std::vector<robot::JointVector> joint_positions;
  std::string method;   // direct, rrt_connect, straight_line
  double planning_time_s = 0;
};

// The state the planner starts from, read from an obs record.
struct StartState {
  robot::JointVector joints = robot::JointVector::Zero();
  double opening_m = 0;
  bool holding = false;  // gripper closed on something: its points near the TCP are ignored
};
StartState start_state_from(const stream::Record& obs);
Goal goal_from(const stream::Record& action);  // throws StreamError on missing/mistyped fields
stream::Record action_record(const Goal& goal);  // pose, gripper_open, ignore_collisions

class MotionPlanner {
 public:
  using Clock = std::chrono::steady_clock;

  MotionPlanner(const robot::RobotModel& robot, const Eigen::Isometry3d& world_from_base,
                PlannerOptions options = {});

  // Builds the scene from every camera of `obs` (<camera>.points + <camera>.extrinsics),
  // with the space around `goal` (if given) taken as free: the agent chose to go there.
  OccupancyScene scene_from(const stream::Record& obs, const StartState& start, const Goal* goal = nullptr) const;

  PlanResult plan(const StartState& start, const Goal& goal, const OccupancyScene& scene,
                  uint64_t plan_index = 0) const;

  const CollisionChecker& collisions() const { return checker_; }
  // Whether this move is a grasp planned with a straight final approach (options.approach_m).
  bool approaches(const StartState& start, const Goal& goal) const;

 private:
  // The steps of plan(): a move that ignores the sensed scene; the goal configuration (the
  // nearest collision-free IK solution); RRT-Connect between start and goal configurations.
  PlanResult plan_ignoring_scene(const StartState& start, const Eigen::Isometry3d& goal_in_base,
                                 robot::IkOptions ik, Clock::time_point t0) const;
  // `accept` (if given) must also hold for the configuration: a grasp's straight approach.
  std::optional<robot::JointVector> goal_configuration(
      const StartState& start, const Eigen::Isometry3d& goal_in_base, const OccupancyScene& scene, robot::IkOptions ik,
      std::string& failure, const std::function<bool(const robot::JointVector&)>& accept = {}) const;
  // A collision-free joint path from the start to goal_q: the direct line, else RRT-Connect
  // (shortcut); empty with `failure` set when there is none.
  std::vector<robot::JointVector> path_to(const StartState& start, const robot::JointVector& goal_q,
                                          const OccupancyScene& scene, uint64_t plan_index, std::string& method,
                                          std::string& failure) const;
  std::vector<robot::JointVector> rrt_connect(const StartState& start, const robot::JointVector& goal_q,
                                              const OccupancyScene& scene, uint64_t plan_index,
                                              std::string& failure) const;
  PlanResult finish(std::vector<robot::JointVector> path, const std::string& method, Clock::time_point t0) const;
  std::vector<robot::JointVector> shortcut(std::vector<robot::JointVector> path, double opening_m,
                                           const OccupancyScene* scene) const;
  bool straight_line(const robot::JointVector& start, const Eigen::Isometry3d& goal_in_base,
                     double opening_m, std::vector<robot::JointVector>& path) const;

  const robot::RobotModel& robot_;
  Eigen::Isometry3d world_from_base_;
  PlannerOptions options_;
  RobotSpheres spheres_;
  CollisionChecker checker_;
};

// plan-path as a library: observations pass through and are remembered; each action passes
// through followed by its trajectory (or failure); other records pass through.
class PlanPathFilter : public stream::Stage {
 public:
  PlanPathFilter(const robot::RobotModel& robot, const Eigen::Isometry3d& world_from_base, PlannerOptions options);
  void handle(const stream::Record& record, const stream::Emit& emit) override;
  std::vector<std::string> reads() const override { return {record_type::action}; }
  // Plans on what `prepare` makes of each observation (point-cloud filters) instead of the
  // observation itself; records still pass through unchanged.
  void observe_through(std::function<stream::Record(const stream::Record&)> prepare) { prepare_ = std::move(prepare); }
  const OccupancyScene* last_scene() const { return scene_.get(); }
  uint64_t plans() const { return plans_; }

 private:
  MotionPlanner planner_;
  std::optional<stream::Record> obs_;
  std::function<stream::Record(const stream::Record&)> prepare_;
  std::unique_ptr<OccupancyScene> scene_;  // of obs_ and the last action
  uint64_t plans_ = 0;
};

// The trajectory record sim-step executes (or one carrying only `failure`).
stream::Record trajectory_record(const PlanResult& plan, const Goal& goal);

}  // namespace qte::planning

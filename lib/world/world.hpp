// The simulated scene: a Bullet dynamics world with a table, the robot driven kinematically
// along joint trajectories, and rigid objects that react physically when pushed. Grasping
// attaches the object between the fingers to the gripper on close, as RLBench does.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "render/camera.hpp"
#include "world/scene_layout.hpp"
#include "robot/robot_model.hpp"

class btCollisionWorld;

namespace qte::world {

// Bullet's collision margin around convex hulls (and compounds of them): a hull rests up to
// this far above what it stands on (cameras see the hull itself). Spawn resting hulls this
// high above their support, one margin each side when stacked (they drop a millimetre at
// most), never lower: hulls that start interpenetrating jump.
constexpr double kHullMargin = 0.001;

struct ObjectSpec {
  enum class Shape { box, cylinder, sphere, convex_hull, compound };
  // What the task makes of the object, for analyses of where an agent went (the codes the
  // observations' objects.role carries): an object the task is about, one that looks like
  // such an object or competes with it (a lookalike), or anything else (zones, bins, boards).
  enum class Role : uint8_t { other = 0, target = 1, distractor = 2 };
  std::string name;
  Role role = Role::other;
  Shape shape = Shape::box;
  Eigen::Vector3d size = Eigen::Vector3d::Constant(0.05);  // box: extents; cylinder: (radius,
                                                           // height, -); sphere: (radius, -, -)
  std::vector<Eigen::Vector3d> hull_points;  // convex_hull: vertices in the object frame
  // compound: a non-convex object as the union of convex hulls (vertices in the object frame),
  // as Bullet collides it and the cameras see it.
  std::vector<std::vector<Eigen::Vector3d>> pieces;
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  double mass_kg = 0.1;     // 0: static (never moves)
  bool collides = true;     // false: seen by cameras only (e.g. a success zone)
  bool graspable = true;
  // The part the fingers close on (object frame), for objects held by a knob or a handle;
  // empty: the whole object, taken as centred on its origin.
  Eigen::AlignedBox3d grasp_region;
  render::Appearance appearance;
};

class World {
 public:
  World(const robot::RobotModel& robot, const SceneLayout& layout = {});
  ~World();
  World(const World&) = delete;
  World& operator=(const World&) = delete;

  const robot::RobotModel& robot() const { return robot_; }
  const SceneLayout& layout() const { return layout_; }
  Eigen::Isometry3d robot_base_pose() const { return layout_.robot_base_pose(); }

  // --- objects --------------------------------------------------------------------------
  int add_object(const ObjectSpec& spec);  // returns the object's id
  int object_count() const;
  const ObjectSpec& object_spec(int id) const;
  int object_id(const std::string& name) const;  // throws Error when absent
  Eigen::Isometry3d object_pose(int id) const;
  // The object's bounding box in its own frame, from its shape (no collision margin).
  Eigen::AlignedBox3d object_box(int id) const;

  // --- the robot ------------------------------------------------------------------------
  // Places the arm and fingers at once (no physics in between): resets and teleports.
  void set_robot_state(const robot::JointVector& q, double finger_opening_m);
  const robot::JointVector& joint_positions() const { return q_; }
  double finger_opening_m() const { return opening_m_; }
  Eigen::Isometry3d tcp_pose() const;  // world frame
  Eigen::Isometry3d link_pose(int link) const;  // world frame

  // Moves the robot kinematically to (q, opening) over dt_s seconds of physics, so objects
  // in the way are pushed. A held object moves with the gripper, except that what it is
  // pressed onto stops it: it slips back in the grip along the approach (a place pose below
  // a board's top leaves the checker on the board, not in it).
  void step_towards(const robot::JointVector& q, double finger_opening_m, double dt_s);
  // Physics only (objects settle), the robot standing still.
  void settle(double seconds);

  // Closes the gripper: the graspable object between the fingers (if any) is held and the
  // fingers stop on its faces. Returns its id or -1.
  int close_gripper();
  void open_gripper();
  int held_object() const { return held_; }
  bool gripper_open() const { return gripper_open_; }  // the last gripper command

  // Robot contacts that make an action fail: a link touching the table or another link
  // (not its neighbours). Empty when none; otherwise a reason such as "collision:link3-table".
  std::string robot_collision() const;

  // The first task object (colliding, not held) a robot link touches deeper than
  // `tolerance_m`, as "<link>-<object>"; empty when none. For checking planned paths.
  std::string robot_object_contact(double tolerance_m = 0.002) const;

  const btCollisionWorld& collision_world() const;
  static constexpr double kPhysicsStep = 1.0 / 240.0;
  // A held object presses this deep into something before it slips (resting contacts and
  // hull margins stay below it); it slips at most kMaxSlip_m at a physics step (a deeper
  // contact, as after a teleport into something, is left as it is).
  static constexpr double kSlipTolerance_m = 0.001, kMaxSlip_m = 0.03;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  const robot::RobotModel& robot_;
  SceneLayout layout_;
  robot::JointVector q_ = robot::JointVector::Zero();
  double opening_m_ = 0;
  int held_ = -1;
  bool gripper_open_ = true;
  Eigen::Isometry3d held_from_tcp_ = Eigen::Isometry3d::Identity();

  void place_robot_links();
  void slip_held_object(const Eigen::Isometry3d& tcp);  // tcp: the pose just placed (world frame)
  void physics_substep();
};

}  // namespace qte::world

// The robot as data: links with primitive collision shapes and joints, read from a URDF file
// (lib/robot/xarm7.urdf by default), and its forward kinematics.
#pragma once

#include <Eigen/Geometry>
#include <string>
#include <vector>

namespace qte::robot {

constexpr int kArmJoints = 7;
// Fingers closed and stopped further apart than this hold something (on nothing they close
// fully): what the simulator needs across the pads to grasp, and what the planner reads as held.
constexpr double kHoldingOpening_m = 0.002;
using JointVector = Eigen::Matrix<double, kArmJoints, 1>;

struct Shape {
  enum class Kind { box, cylinder, sphere };
  Kind kind = Kind::box;
  Eigen::Vector3d size = Eigen::Vector3d::Zero();  // box: full extents; cylinder: (radius,
                                                   // length along z, 0); sphere: (radius,0,0)
  Eigen::Isometry3d link_from_shape = Eigen::Isometry3d::Identity();
};

struct Link {
  std::string name;
  std::vector<Shape> shapes;  // collision primitives, in the link frame
  Eigen::Vector3f colour{0.9f, 0.9f, 0.9f};
  int parent_joint = -1;  // index into joints(); -1 for the base
};

struct Joint {
  enum class Type { revolute, prismatic, fixed };
  std::string name;
  Type type = Type::fixed;
  int parent_link = 0, child_link = 0;
  Eigen::Isometry3d origin = Eigen::Isometry3d::Identity();  // parent link -> joint frame
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();
  double lower = 0, upper = 0, max_velocity = 0;
  int arm_index = -1;   // 0..6 for the arm's revolute joints
  bool finger = false;  // a prismatic gripper finger, driven by the opening width
};

class RobotModel {
 public:
  // Parses a URDF file (liburdfdom). It must hold one chain of 7 revolute joints from the
  // root link to a link named "tcp", and prismatic finger joints (named "*finger*").
  static RobotModel load_urdf(const std::string& path);
  // The toolkit's xArm 7: $QTE_DATA_DIR/xarm7.urdf, else the copy in share/qte beside the
  // program (PREFIX/share/qte installed, BUILD/share/qte in a build tree).
  static RobotModel xarm7();

  const std::vector<Link>& links() const { return links_; }
  const std::vector<Joint>& joints() const { return joints_; }
  int link_index(const std::string& name) const;  // throws Error when absent
  int tcp_link() const { return tcp_link_; }

  JointVector lower_limits() const;
  JointVector upper_limits() const;
  JointVector max_velocities() const;
  double max_finger_opening_m() const { return max_opening_m_; }  // both fingers together

  // Pairs of links (with collision shapes) that must not touch: links more than two moving
  // joints apart. Neighbours overlap at their joints by construction; the fingers move with
  // the gripper, so they count as one group with it.
  std::vector<std::pair<int, int>> self_collision_pairs() const;

  // Pose of every link in the robot's base frame for arm joints `q` (rad) and a gripper
  // opening (distance between the fingers, m).
  std::vector<Eigen::Isometry3d> link_poses(const JointVector& q, double opening_m) const;
  Eigen::Isometry3d tcp_pose(const JointVector& q) const;
  // Geometric Jacobian of the TCP (rows: linear xyz, angular xyz; base frame).
  Eigen::Matrix<double, 6, kArmJoints> tcp_jacobian(const JointVector& q) const;

 private:
  std::vector<Link> links_;
  std::vector<Joint> joints_;  // in topological order: a joint's parent link comes first
  int tcp_link_ = -1;
  double max_opening_m_ = 0;
};

std::string default_data_dir();
// What the programs that load the robot say of it in their ENVIRONMENT section.
extern const char* const kDataDirEnvironment;

}  // namespace qte::robot

// Saved camera frames made into 'obs' records (formats/record-stream.md), so the learned agent
// runs on a real RGB-D camera's data: a colour PNG with a 16-bit depth PNG, or a .pcd cloud, plus
// the camera's intrinsics and pose and, when known, the robot's joint state. The world frame is
// the simulation's (robot base at world::SceneLayout's pose), so the scene bounds and networks
// trained in simulation apply.
#pragma once

#include <Eigen/Geometry>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "observation/observation.hpp"
#include "robot/robot_model.hpp"
#include "stream/record.hpp"
#include "voxels/observation_cloud.hpp"

namespace qte::camera_recordings {

struct CameraSetup {
  std::string name = "front";                 // field prefix: <name>.rgb, <name>.depth_mm, ...
  std::optional<Eigen::Matrix3d> intrinsics;  // pinhole K; needed for depth images
  Eigen::Isometry3d camera_to_world = Eigen::Isometry3d::Identity();  // OpenCV axes: x right, y down, z forward
  double depth_unit_m = 0.001;                // metres per depth count (RealSense: 0.001)
  bool store_points = true;                   // also write <name>.points (plan-path needs them)
};

// The robot at one frame: arm joints (rad) and the distance between the fingers (m); from a
// time-stamped joint log (joint_log.hpp) also the joints' velocities and, when the log has it,
// whether the gripper is open (closed on an object, the fingers may stand more than half open).
struct RobotState {
  robot::JointVector joints = robot::JointVector::Zero();
  double gripper_opening_m = 0.085;
  robot::JointVector joint_velocities_rad_s = robot::JointVector::Zero();
  std::optional<bool> gripper_open;  // none: open when the fingers are more than half open
};

// Adds the camera's fields for a colour image (8-bit, 3 channels, BGR as OpenCV reads it) and a
// depth image (16-bit, one channel, 0 = no return). Depth in millimetres is stored as is
// (<name>.depth_mm, the replay's own form); any other unit as float metres (<name>.depth).
// Throws Error naming `what` (the files) when the images do not fit together or the setup.
void add_camera_images(stream::Record& obs, const CameraSetup& camera, const cv::Mat& bgr, const cv::Mat& depth,
                       const std::string& what);

// Adds the camera's fields for a cloud given in the camera frame (as a sensor's driver saves
// it): <name>.points in the world frame, <name>.rgb, and the intrinsics when set.
void add_camera_cloud(stream::Record& obs, const CameraSetup& camera, const voxels::CameraCloud& cloud);

// The arm's fields of an observation (observation::set_arm_state) from a recorded state: the
// gripper's pose by forward kinematics, gripper_open the state's, else fingers more than half open.
observation::ArmState arm_state(const RobotState& state, const robot::RobotModel& robot,
                               const Eigen::Isometry3d& world_from_base);
bool gripper_is_open(const RobotState& state, const robot::RobotModel& robot);

// A CSV with one row per frame: 7 joint angles in radians, optionally the gripper opening in
// metres as an 8th column; a first row with no number in it is a header (nan and inf are
// numbers: a row of them is data, and refused). Every cell must be a finite number. Throws
// Error naming the file, line, column and what was expected; joints outside the robot's
// limits and a file without rows are refused.
std::vector<RobotState> read_joint_csv(const std::string& path, const robot::RobotModel& robot);

}  // namespace qte::camera_recordings

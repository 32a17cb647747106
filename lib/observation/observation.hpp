// The fields of an 'obs' record (formats/record-stream.md, section 3), written in one place for
// every program that observes: the simulator (sim-step, demo-record), saved camera recordings
// (obs-pack) and a real robot (robot-step). Each writer fills these values; the names, dtypes,
// shapes and order of the fields are this module's.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <optional>
#include <string>

#include "robot/robot_model.hpp"
#include "stream/record.hpp"

namespace qte::observation {

// <camera>.intrinsics (3x3, when known) and <camera>.extrinsics (4x4, the camera's pose in the
// world), row-major.
void set_camera_pose(stream::Record& obs, const std::string& camera, const std::optional<Eigen::Matrix3d>& intrinsics,
                     const Eigen::Isometry3d& world_from_camera);

// The arm's state. Without joints (a recording with no joint log) only the gripper's fields.
struct ArmState {
  std::optional<robot::JointVector> joints;  // radians
  robot::JointVector velocities_rad_s = robot::JointVector::Zero();
  Eigen::Isometry3d tool_in_world = Eigen::Isometry3d::Identity();  // the gripper's tool point
  bool gripper_open = true;
  double gripper_opening_m = 0;
};
// joint_positions, joint_velocities, gripper_pose (when the joints are known), gripper_open,
// gripper_opening_m.
void set_arm_state(stream::Record& obs, const ArmState& arm);

// Where the observation stands in its episode.
struct EpisodeState {
  int step = 0;            // actions taken so far in the episode
  int episode_length = 0;  // actions allowed
  int frame = 0;           // observations of the stream before this one
  double time_s = 0;
  float reward = 0;
  bool terminal = false, success = false;
  std::string task;
  int variation = 0;
  int64_t episode_seed = 0;
  std::string description;
  bool ignore_collisions = false;
  std::string failure;  // why the episode ended early, or empty
};
// step, episode_length, frame, time_s, reward, terminal, success, task, variation, episode_seed,
// description, ignore_collisions, and failure when there is one.
void set_episode_state(stream::Record& obs, const EpisodeState& episode);

}  // namespace qte::observation

// A saved recording made into a stream of 'obs' records, what obs-pack does: frames named by a
// printf-style pattern, read from a first index until the first missing one (or exactly a
// count), each with the camera's setup, the robot's state from a joint log when there is one,
// and the fields of one episode of `episode_length` steps after another, or of one recorded
// demonstration.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "camera_recordings/camera_recordings.hpp"
#include "camera_recordings/joint_log.hpp"

namespace qte::camera_recordings {

// The pattern with its one integer conversion (%d, %06d, %i, %u with flags and width) filled in
// with `index`; anything else ('%s', two conversions) is a UsageError, never handed to printf.
std::string frame_path(const std::string& pattern, int64_t index);

// The camera's pose from the options' values: x, y, z, qx, qy, qz, qw (a unit quaternion), or a
// row-major 4x4 camera-to-world matrix (a proper rotation); UsageError naming `option` otherwise.
Eigen::Isometry3d camera_pose_from_values(const std::vector<double>& values, const std::string& option);
Eigen::Isometry3d camera_pose_from_matrix(const std::vector<double>& values, const std::string& option);
// K from fx, fy, cx, cy; UsageError naming `option` when it is not a camera's.
Eigen::Matrix3d intrinsics_from_values(const std::vector<double>& values, const std::string& option);

struct Recording {
  std::string rgb_pattern, depth_pattern;  // colour and 16-bit depth PNGs, or
  std::string pcd_pattern;                 // point clouds in the camera frame
  int64_t start = 0;
  int64_t count = -1;  // -1: until the first missing frame
  int episode_length = 10;
  std::string task;
  CameraSetup camera;
  std::string joints_path;         // the file whose rows gave the states: joint CSV or frame times ("" for none)
  std::vector<RobotState> states;  // one per frame written, from the first
  std::vector<double> times_s;     // each frame's time, from the first frame's (empty: all 0)
  // One whole demonstration that succeeded or not: frames numbered from 0, steps as
  // demo-record's (0 at the first frame, then 1 + the keyframes before the frame: the motion it
  // belongs to), the last frame terminal with the success and its reward. Needs every frame's
  // state (count, or one state per frame).
  std::optional<bool> demonstration_success;
};

// The robot's state at each frame from a joint log at the frames' times, and the frames' times
// from the first frame's; the frames are the ones timed (the count, unless set). Error naming
// the frame times' line when one is outside the log's span.
void add_joint_log(Recording& recording, const JointLog& log, const FrameTimes& frames);

// The step of each frame of a demonstration, as demo-record numbers them: 0 at the first frame,
// then 1 + the keyframes (keyframe's rule, on the states' joint velocities and gripper) before
// the frame.
std::vector<int> demonstration_steps(const std::vector<RobotState>& states, const robot::RobotModel& robot);

struct PackedRecording {
  int64_t written = 0;
  int64_t blind = 0;  // frames with no point inside the default scene bounds
};

// Emits one 'obs' per frame. Throws Error naming the file of a missing or damaged frame, the
// joint log when it has fewer rows than frames, and the first frame when there is none.
PackedRecording pack_recording(const Recording& recording, const robot::RobotModel& robot,
                               const std::function<void(const stream::Record&)>& emit);

}  // namespace qte::camera_recordings

#include "camera_recordings/recording.hpp"

#include <sys/stat.h>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <cstring>

#include "camera_recordings/png_frames.hpp"
#include "common/error.hpp"
#include "observation/observation.hpp"
#include "keyframes/keyframes.hpp"
#include "point_clouds/pcd_file.hpp"
#include "robot/pose_values.hpp"
#include "stream/field_names.hpp"
#include "tasks/episode.hpp"
#include "voxels/observation_cloud.hpp"
#include "world/scene_layout.hpp"

namespace qte::camera_recordings {

std::string frame_path(const std::string& pattern, int64_t index) {
  std::string out;
  int conversions = 0;
  for (std::size_t i = 0; i < pattern.size(); ++i) {
    if (pattern[i] != '%') {
      out += pattern[i];
      continue;
    }
    if (i + 1 < pattern.size() && pattern[i + 1] == '%') {
      out += '%';
      ++i;
      continue;
    }
    std::size_t j = i + 1;
    while (j < pattern.size() && std::strchr("-+ 0#", pattern[j])) ++j;
    while (j < pattern.size() && std::isdigit(static_cast<unsigned char>(pattern[j]))) ++j;
    if (j >= pattern.size() || !std::strchr("diu", pattern[j]) || ++conversions > 1)
      throw UsageError("file pattern '" + pattern + "': expected exactly one integer conversion such as %06d");
    char number[64];
    std::snprintf(number, sizeof number, ("%" + pattern.substr(i + 1, j - i - 1) + "lld").c_str(),
                  static_cast<long long>(index));
    out += number;
    i = j;
  }
  if (conversions != 1) throw UsageError("file pattern '" + pattern + "': expected one integer conversion such as %06d");
  return out;
}

Eigen::Isometry3d camera_pose_from_values(const std::vector<double>& values, const std::string& option) {
  if (values.size() != robot::kPoseValues || !robot::pose_values_valid(values.data()))
    throw UsageError("--" + option + ": expected x, y, z, qx, qy, qz, qw with a unit quaternion");
  return robot::pose_from_values(values.data());
}

Eigen::Isometry3d camera_pose_from_matrix(const std::vector<double>& values, const std::string& option) {
  const std::string problem = values.size() == 16 ? voxels::extrinsics_problem(values.data()) : "16 numbers";
  if (!problem.empty()) throw UsageError("--" + option + ": expected " + problem);
  Eigen::Isometry3d pose;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) pose.matrix()(r, c) = values[4 * r + c];
  return pose;
}

Eigen::Matrix3d intrinsics_from_values(const std::vector<double>& values, const std::string& option) {
  if (values.size() != 4) throw UsageError("--" + option + ": expected fx, fy, cx, cy");
  Eigen::Matrix<double, 3, 3, Eigen::RowMajor> k;
  k << values[0], 0, values[2], 0, values[1], values[3], 0, 0, 1;
  const std::string problem = voxels::intrinsics_problem(k.data());
  if (!problem.empty()) throw UsageError("--" + option + ": expected " + problem);
  return k;
}

namespace {
bool exists(const std::string& path) {
  struct stat st;
  return ::stat(path.c_str(), &st) == 0;
}
}  // namespace

void add_joint_log(Recording& recording, const JointLog& log, const FrameTimes& frames) {
  recording.joints_path = frames.path;
  recording.states = states_at(log, frames);
  recording.times_s.clear();
  for (double t : frames.times_s) recording.times_s.push_back(t - frames.times_s.front());
  if (recording.count < 0) recording.count = static_cast<int64_t>(frames.times_s.size());
}

std::vector<int> demonstration_steps(const std::vector<RobotState>& states, const robot::RobotModel& robot) {
  std::vector<keyframes::FrameState> frames(states.size());
  for (std::size_t i = 0; i < states.size(); ++i) {
    frames[i].gripper_open = gripper_is_open(states[i], robot);
    for (int k = 0; k < robot::kArmJoints; ++k) frames[i].joint_velocities[k] = states[i].joint_velocities_rad_s[k];
  }
  const std::vector<int> keyframes = keyframes::discover_keyframes(frames);
  std::vector<int> steps(states.size(), 0);
  for (std::size_t i = 1; i < steps.size(); ++i)
    steps[i] = 1 + static_cast<int>(std::lower_bound(keyframes.begin(), keyframes.end(), static_cast<int>(i)) -
                                    keyframes.begin());
  return steps;
}

PackedRecording pack_recording(const Recording& recording, const robot::RobotModel& robot,
                               const std::function<void(const stream::Record&)>& emit) {
  const bool images = recording.pcd_pattern.empty();
  const std::string& pattern = images ? recording.rgb_pattern : recording.pcd_pattern;
  const bool has_states = !recording.joints_path.empty();
  int64_t count = recording.count;
  std::vector<int> steps;  // a demonstration's
  if (recording.demonstration_success) {
    // Its steps and its end need every frame's state before the first frame is packed.
    if (!has_states)
      throw Error("a demonstration needs the robot's state at every frame (its keyframes are found from them)");
    if (count < 0) count = static_cast<int64_t>(recording.states.size());
    if (static_cast<int64_t>(recording.states.size()) < count)
      throw Error(recording.joints_path + ": " + std::to_string(recording.states.size()) +
                  " rows for a demonstration of " + std::to_string(count) + " frames, expected one row per frame");
    if (count < 2)
      throw Error(recording.joints_path + ": a demonstration of " + std::to_string(count) +
                  " frame, expected at least two");
    steps = demonstration_steps({recording.states.begin(), recording.states.begin() + count}, robot);
  }
  PackedRecording packed;
  for (int64_t index = recording.start; count < 0 || packed.written < count; ++index) {
    const std::string first = frame_path(pattern, index);
    if (!exists(first)) {
      if (count >= 0)
        throw Error(first + ": no such frame (" + std::to_string(count) + " frames from " +
                    std::to_string(recording.start) + ")");
      break;
    }
    stream::Record obs(record_type::obs);
    if (images) {
      const std::string depth_path = frame_path(recording.depth_pattern, index);
      add_camera_images(obs, recording.camera, read_colour_png(first), read_depth_png(depth_path),
                        first + " and " + depth_path);
    } else {
      add_camera_cloud(obs, recording.camera, point_clouds::read_pcd(first));
    }
    observation::ArmState arm;  // without a joint log: the gripper open, nothing else known
    arm.gripper_opening_m = robot.max_finger_opening_m();
    if (has_states) {
      if (packed.written >= static_cast<int64_t>(recording.states.size()))
        throw Error(recording.joints_path + ": no row for frame " + std::to_string(index) + " (" +
                    std::to_string(recording.states.size()) + " rows)");
      arm = arm_state(recording.states[packed.written], robot, world::SceneLayout{}.robot_base_pose());
    }
    observation::set_arm_state(obs, arm);
    observation::EpisodeState episode;  // an episode that has not ended, unless a demonstration's last frame
    episode.step = episode.frame = static_cast<int>(packed.written);
    episode.episode_length = recording.episode_length;
    episode.task = recording.task;
    if (!recording.times_s.empty()) episode.time_s = recording.times_s.at(packed.written);
    if (recording.demonstration_success) {
      episode.step = steps[packed.written];
      if (packed.written + 1 == count) {
        episode.success = *recording.demonstration_success;
        episode.reward = episode.success ? tasks::kSuccessReward : 0.0f;
        episode.terminal = true;
      }
    }
    observation::set_episode_state(obs, episode);
    const voxels::ObservationCloud cloud = voxels::observation_cloud(obs);
    if (voxels::points_inside(cloud.view(), voxels::GridBounds{}) == 0) packed.blind += 1;
    emit(obs);
    packed.written += 1;
  }
  if (packed.written == 0) throw Error(frame_path(pattern, recording.start) + ": no such frame");
  return packed;
}

}  // namespace qte::camera_recordings

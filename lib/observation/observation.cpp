#include "observation/observation.hpp"

#include <vector>

#include "robot/pose_values.hpp"
#include "stream/field_names.hpp"

namespace qte::observation {

namespace {

std::vector<double> row_major(const Eigen::Matrix3d& m) {
  return {m(0, 0), m(0, 1), m(0, 2), m(1, 0), m(1, 1), m(1, 2), m(2, 0), m(2, 1), m(2, 2)};
}

std::vector<double> row_major(const Eigen::Isometry3d& t) {
  std::vector<double> v(16);
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) v[4 * r + c] = t.matrix()(r, c);
  return v;
}

}  // namespace

void set_camera_pose(stream::Record& obs, const std::string& camera, const std::optional<Eigen::Matrix3d>& intrinsics,
                     const Eigen::Isometry3d& world_from_camera) {
  if (intrinsics) obs.set<double>(camera + fields::per_camera::intrinsics, {3, 3}, row_major(*intrinsics));
  obs.set<double>(camera + fields::per_camera::extrinsics, {4, 4}, row_major(world_from_camera));
}

void set_arm_state(stream::Record& obs, const ArmState& arm) {
  if (arm.joints) {
    obs.set<double>(fields::joint_positions, {robot::kArmJoints}, arm.joints->data());
    obs.set<double>(fields::joint_velocities, {robot::kArmJoints}, arm.velocities_rad_s.data());
    obs.set<double>(fields::gripper_pose, {robot::kPoseValues}, robot::pose_values(arm.tool_in_world));
  }
  obs.set_scalar<uint8_t>(fields::gripper_open, arm.gripper_open);
  obs.set_scalar<double>(fields::gripper_opening_m, arm.gripper_opening_m);
}

void set_episode_state(stream::Record& obs, const EpisodeState& e) {
  obs.set_scalar<int32_t>(fields::step, e.step);
  obs.set_scalar<int32_t>(fields::episode_length, e.episode_length);
  obs.set_scalar<int32_t>(fields::frame, e.frame);
  obs.set_scalar<double>(fields::time_s, e.time_s);
  obs.set_scalar<float>(fields::reward, e.reward);
  obs.set_scalar<uint8_t>(fields::terminal, e.terminal);
  obs.set_scalar<uint8_t>(fields::success, e.success);
  obs.set_string(fields::task, e.task);
  obs.set_scalar<int32_t>(fields::variation, e.variation);
  obs.set_scalar<int64_t>(fields::episode_seed, e.episode_seed);
  obs.set_string(fields::description, e.description);
  obs.set_scalar<uint8_t>(fields::ignore_collisions, e.ignore_collisions);
  if (!e.failure.empty()) obs.set_string(fields::failure, e.failure);
}

}  // namespace qte::observation

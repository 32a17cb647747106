#include "camera_recordings/camera_recordings.hpp"

#include "common/error.hpp"
#include "stream/field_names.hpp"

namespace qte::camera_recordings {

void add_camera_images(stream::Record& obs, const CameraSetup& camera, const cv::Mat& bgr, const cv::Mat& depth,
                       const std::string& what) {
  if (bgr.type() != CV_8UC3) throw Error(what + ": expected an 8-bit colour image");
  if (depth.type() != CV_16UC1) throw Error(what + ": expected a 16-bit single-channel depth image");
  if (bgr.size() != depth.size())
    throw Error(what + ": colour " + std::to_string(bgr.cols) + "x" + std::to_string(bgr.rows) + " and depth " +
                std::to_string(depth.cols) + "x" + std::to_string(depth.rows) + " differ in size");
  if (!camera.intrinsics) throw Error(what + ": depth images need the camera's intrinsics (--intrinsics)");
  const int h = bgr.rows, w = bgr.cols;
  std::vector<uint8_t> rgb(static_cast<std::size_t>(h) * w * 3);
  for (int v = 0; v < h; ++v)
    for (int u = 0; u < w; ++u) {
      const cv::Vec3b p = bgr.at<cv::Vec3b>(v, u);
      uint8_t* out = &rgb[3 * (static_cast<std::size_t>(v) * w + u)];
      out[0] = p[2], out[1] = p[1], out[2] = p[0];
    }
  std::vector<uint16_t> counts(static_cast<std::size_t>(h) * w);
  for (int v = 0; v < h; ++v)
    for (int u = 0; u < w; ++u) counts[static_cast<std::size_t>(v) * w + u] = depth.at<uint16_t>(v, u);
  obs.set<uint8_t>(camera.name + fields::per_camera::rgb, {h, w, 3}, rgb);
  if (camera.depth_unit_m == 0.001) {
    obs.set<uint16_t>(camera.name + fields::per_camera::depth_mm, {h, w}, counts);
  } else {
    std::vector<float> metres(counts.size());
    for (std::size_t i = 0; i < counts.size(); ++i) metres[i] = static_cast<float>(counts[i] * camera.depth_unit_m);
    obs.set<float>(camera.name + fields::per_camera::depth, {h, w}, metres);
  }
  observation::set_camera_pose(obs, camera.name, camera.intrinsics, camera.camera_to_world);
  if (camera.store_points) {
    // The points every reader would rebuild from the depth, once (plan-path needs them stored).
    for (const voxels::CameraCloud& c : voxels::camera_clouds(obs))
      if (c.camera == camera.name) obs.set<float>(camera.name + fields::per_camera::points, {h, w, 3}, c.cloud.xyz);
  }
}

void add_camera_cloud(stream::Record& obs, const CameraSetup& camera, const voxels::CameraCloud& cloud) {
  std::vector<float> world(cloud.cloud.xyz.size());
  for (std::size_t i = 0; i < world.size(); i += 3) {
    const Eigen::Vector3d p(cloud.cloud.xyz[i], cloud.cloud.xyz[i + 1], cloud.cloud.xyz[i + 2]);
    const Eigen::Vector3f q = (camera.camera_to_world * p).cast<float>();  // NaN stays NaN
    world[i] = q.x(), world[i + 1] = q.y(), world[i + 2] = q.z();
  }
  obs.set<uint8_t>(camera.name + fields::per_camera::rgb, {cloud.height, cloud.width, 3}, cloud.cloud.rgb);
  obs.set<float>(camera.name + fields::per_camera::points, {cloud.height, cloud.width, 3}, world);
  observation::set_camera_pose(obs, camera.name, camera.intrinsics, camera.camera_to_world);
}

observation::ArmState arm_state(const RobotState& state, const robot::RobotModel& robot,
                               const Eigen::Isometry3d& world_from_base) {
  observation::ArmState arm;
  arm.joints = state.joints;
  arm.velocities_rad_s = state.joint_velocities_rad_s;
  arm.tool_in_world = world_from_base * robot.tcp_pose(state.joints);
  arm.gripper_open = gripper_is_open(state, robot);
  arm.gripper_opening_m = state.gripper_opening_m;
  return arm;
}

bool gripper_is_open(const RobotState& state, const robot::RobotModel& robot) {
  return state.gripper_open.value_or(state.gripper_opening_m > robot.max_finger_opening_m() / 2);
}

}  // namespace qte::camera_recordings

#include "camera_recordings/camera_recordings.hpp"

#include <cmath>
#include <cstdlib>
#include <fstream>

#include "common/error.hpp"
#include "robot/pose_values.hpp"

namespace qte::camera_recordings {

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

void add_pose_fields(stream::Record& obs, const CameraSetup& camera) {
  if (camera.intrinsics) obs.set<double>(camera.name + ".intrinsics", {3, 3}, row_major(*camera.intrinsics));
  obs.set<double>(camera.name + ".extrinsics", {4, 4}, row_major(camera.camera_to_world));
}

}  // namespace

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
  obs.set<uint8_t>(camera.name + ".rgb", {h, w, 3}, rgb);
  if (camera.depth_unit_m == 0.001) {
    obs.set<uint16_t>(camera.name + ".depth_mm", {h, w}, counts);
  } else {
    std::vector<float> metres(counts.size());
    for (std::size_t i = 0; i < counts.size(); ++i) metres[i] = static_cast<float>(counts[i] * camera.depth_unit_m);
    obs.set<float>(camera.name + ".depth", {h, w}, metres);
  }
  add_pose_fields(obs, camera);
  if (camera.store_points) {
    // The points every reader would rebuild from the depth, once (plan-path needs them stored).
    for (const voxels::CameraCloud& c : voxels::camera_clouds(obs))
      if (c.camera == camera.name) obs.set<float>(camera.name + ".points", {h, w, 3}, c.cloud.xyz);
  }
}

void add_camera_cloud(stream::Record& obs, const CameraSetup& camera, const voxels::CameraCloud& cloud) {
  std::vector<float> world(cloud.cloud.xyz.size());
  for (std::size_t i = 0; i < world.size(); i += 3) {
    const Eigen::Vector3d p(cloud.cloud.xyz[i], cloud.cloud.xyz[i + 1], cloud.cloud.xyz[i + 2]);
    const Eigen::Vector3f q = (camera.camera_to_world * p).cast<float>();  // NaN stays NaN
    world[i] = q.x(), world[i + 1] = q.y(), world[i + 2] = q.z();
  }
  obs.set<uint8_t>(camera.name + ".rgb", {cloud.height, cloud.width, 3}, cloud.cloud.rgb);
  obs.set<float>(camera.name + ".points", {cloud.height, cloud.width, 3}, world);
  add_pose_fields(obs, camera);
}

void add_robot_state(stream::Record& obs, const RobotState& state, const robot::RobotModel& robot,
                     const Eigen::Isometry3d& world_from_base) {
  const Eigen::Isometry3d tcp = world_from_base * robot.tcp_pose(state.joints);
  obs.set<double>("joint_positions", {robot::kArmJoints}, state.joints.data());
  obs.set<double>("joint_velocities", {robot::kArmJoints}, std::vector<double>(robot::kArmJoints, 0.0));
  obs.set<double>("gripper_pose", {robot::kPoseValues}, robot::pose_values(tcp));
  obs.set_scalar<uint8_t>("gripper_open", state.gripper_opening_m > robot.max_finger_opening_m() / 2);
  obs.set_scalar<double>("gripper_opening_m", state.gripper_opening_m);
}

void add_episode_fields(stream::Record& obs, int step, int episode_length, const std::string& task) {
  obs.set_scalar<int32_t>("step", step);
  obs.set_scalar<int32_t>("frame", step);
  obs.set_scalar<int32_t>("episode_length", episode_length);
  obs.set_scalar<double>("time_s", 0.0);
  obs.set_scalar<float>("reward", 0.0f);
  obs.set_scalar<uint8_t>("terminal", 0);
  obs.set_scalar<uint8_t>("success", 0);
  obs.set_scalar<uint8_t>("ignore_collisions", 0);
  obs.set_string("task", task);
  obs.set_string("description", "");
  obs.set_scalar<int32_t>("variation", 0);
  obs.set_scalar<int64_t>("episode_seed", 0);
}

namespace {

// One CSV cell: a finite number, a number that is not finite (nan, inf, 1e999) or not a number.
enum class Cell { finite, not_finite, not_a_number };

Cell read_cell(const std::string& text, double& value) {
  const char* s = text.c_str();
  char* end = nullptr;
  value = std::strtod(s, &end);
  while (end && (*end == ' ' || *end == '\t' || *end == '\r')) ++end;
  if (end == s || *end != '\0') return Cell::not_a_number;
  return std::isfinite(value) ? Cell::finite : Cell::not_finite;
}

// Cells between commas: "a,,b," is four cells, the second and last empty.
std::vector<std::string> cells_of(const std::string& line) {
  std::vector<std::string> cells(1);
  for (char c : line) {
    if (c == ',') cells.emplace_back();
    else cells.back() += c;
  }
  return cells;
}

std::string shown(std::string cell) {
  while (!cell.empty() && (cell.back() == '\r' || cell.back() == ' ')) cell.pop_back();
  if (cell.empty()) return "empty";
  if (cell.size() > 32) return "a " + std::to_string(cell.size()) + "-character text";
  for (char& c : cell)
    if (c < 0x20 || c > 0x7e) c = '?';
  return "'" + cell + "'";
}

}  // namespace

std::vector<RobotState> read_joint_csv(const std::string& path, const robot::RobotModel& robot) {
  std::ifstream in(path);
  if (!in) throw_system_error("cannot open " + path);
  std::vector<RobotState> states;
  const robot::JointVector lo = robot.lower_limits(), hi = robot.upper_limits();
  const std::string columns = "7 joint angles in radians, then optionally the gripper opening in metres";
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    if (line.empty() || line == "\r" || line[0] == '#') continue;
    const std::vector<std::string> cells = cells_of(line);
    std::vector<double> values(cells.size());
    std::vector<Cell> kinds(cells.size());
    bool any_number = false;
    for (std::size_t c = 0; c < cells.size(); ++c) {
      kinds[c] = read_cell(cells[c], values[c]);
      any_number = any_number || kinds[c] != Cell::not_a_number;
    }
    // A first line of names is a header; "nan" or "inf" reads as a number, so a row of them is data.
    if (number == 1 && !any_number) continue;
    const std::string where = path + ": line " + std::to_string(number) + ": ";
    for (std::size_t c = 0; c < cells.size(); ++c)
      if (kinds[c] != Cell::finite)
        throw Error(where + "column " + std::to_string(c + 1) + " is " + shown(cells[c]) + ", expected a finite number (" +
                    columns + ")");
    if (values.size() != 7 && values.size() != 8)
      throw Error(where + std::to_string(values.size()) + " columns, expected 7 or 8 (" + columns + ")");
    RobotState s;
    for (int k = 0; k < robot::kArmJoints; ++k) {
      s.joints[k] = values[k];
      if (values[k] < lo[k] - 1e-6 || values[k] > hi[k] + 1e-6)
        throw Error(where + "joint " + std::to_string(k + 1) + " at " + std::to_string(values[k]) +
                    " rad is outside its limits (" + std::to_string(lo[k]) + ", " + std::to_string(hi[k]) +
                    "); are the angles in degrees?");
    }
    if (values.size() == 8) {
      if (!(values[7] >= 0 && values[7] <= robot.max_finger_opening_m() + 1e-6))
        throw Error(where + "gripper opening " + std::to_string(values[7]) + " m is outside 0.." +
                    std::to_string(robot.max_finger_opening_m()));
      s.gripper_opening_m = values[7];
    } else {
      s.gripper_opening_m = robot.max_finger_opening_m();
    }
    states.push_back(s);
  }
  if (in.bad()) throw_system_error("cannot read " + path);
  if (states.empty()) throw Error(path + ": no rows, expected one row per frame (" + columns + ")");
  return states;
}

}  // namespace qte::camera_recordings

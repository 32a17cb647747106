#include "robot/xarm_export.hpp"

#include <cmath>
#include <cstdio>

#include "common/error.hpp"

namespace qte::robot {

int xarm_gripper_units(double opening_m, const RobotModel& robot) {
  const double fraction = std::clamp(opening_m / robot.max_finger_opening_m(), 0.0, 1.0);
  return static_cast<int>(std::lround(fraction * kXarmGripperOpenUnits));
}

std::vector<XarmRow> xarm_rows(const double* time_s, const double* joints, int64_t n, double gripper_before_m,
                               double gripper_after_m, const RobotModel& robot, double rate_hz, double settle_s) {
  if (n < 1) throw Error("an empty path");
  const std::string failure = joint_path_failure(time_s, joints, n, robot);
  if (!failure.empty()) throw Error("the planned path cannot be executed: " + failure);
  const double duration = time_s[n - 1];
  const int64_t ticks = static_cast<int64_t>(std::ceil(duration * rate_hz - 1e-9));
  std::vector<double> times;
  std::vector<double> sampled;
  for (int64_t i = 0; i <= ticks; ++i) {
    const double t = std::min(duration, static_cast<double>(i) / rate_hz);
    if (!times.empty() && t <= times.back()) break;
    // A tick a hair before the end would print with the end's time: the end stands for both.
    if (i < ticks && duration - t < 1e-4) continue;
    const JointVector q = joint_path_at(time_s, joints, n, t);
    times.push_back(t);
    sampled.insert(sampled.end(), q.data(), q.data() + kArmJoints);
  }
  // Sampling a piecewise-linear path cannot speed it up, but say so by checking, not by argument.
  const std::string resampled = joint_path_failure(times.data(), sampled.data(), static_cast<int64_t>(times.size()), robot);
  if (!resampled.empty()) throw Error("the path sampled at " + std::to_string(rate_hz) + " Hz: " + resampled);
  std::vector<XarmRow> rows;
  const int before = xarm_gripper_units(gripper_before_m, robot);
  for (std::size_t i = 0; i < times.size(); ++i) {
    XarmRow row;
    row.time_s = times[i];
    for (int k = 0; k < kArmJoints; ++k) row.degrees[k] = sampled[i * kArmJoints + k] * 180.0 / M_PI;
    row.gripper = before;
    rows.push_back(row);
  }
  XarmRow last = rows.back();
  last.time_s += settle_s;
  last.gripper = xarm_gripper_units(gripper_after_m, robot);
  rows.push_back(last);
  return rows;
}

std::string xarm_csv(const std::vector<XarmRow>& rows, const std::string& comment) {
  std::string out = comment + "time_s,j1_deg,j2_deg,j3_deg,j4_deg,j5_deg,j6_deg,j7_deg,gripper\n";
  char line[512];
  for (const XarmRow& r : rows) {
    int used = std::snprintf(line, sizeof line, "%.6f", r.time_s);
    for (int k = 0; k < kArmJoints; ++k) used += std::snprintf(line + used, sizeof line - used, ",%.6f", r.degrees[k]);
    std::snprintf(line + used, sizeof line - used, ",%d\n", r.gripper);
    out += line;
  }
  return out;
}

std::vector<XarmRow> XarmEpisode::motion(const double* time_s, const double* joints, int64_t n,
                                         bool gripper_open_after) {
  const double before_m = gripper_m_.value_or(robot_.max_finger_opening_m());
  const double after_m = gripper_open_after ? robot_.max_finger_opening_m() : 0.0;
  std::vector<XarmRow> rows = xarm_rows(time_s, joints, n, before_m, after_m, robot_, rate_hz_, settle_s_);
  gripper_m_ = after_m;  // only once the motion is accepted
  return rows;
}

}  // namespace qte::robot

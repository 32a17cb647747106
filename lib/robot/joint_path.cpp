#include "robot/joint_path.hpp"

#include <algorithm>
#include <cmath>

namespace qte::robot {

std::string joint_path_failure(const double* times, const double* joints, int64_t n, const RobotModel& robot,
                               const JointPathLimits& limits) {
  for (int64_t i = 0; i < n * kArmJoints; ++i)
    if (!std::isfinite(joints[i])) return "invalid_trajectory:not_finite";
  for (int64_t i = 0; i < n; ++i)
    if (!std::isfinite(times[i]) || (i > 0 && times[i] <= times[i - 1]) || (i == 0 && times[0] != 0))
      return "invalid_trajectory:time_s must start at 0 and increase";
  if (times[n - 1] > limits.max_duration_s)
    return "invalid_trajectory:longer than " + std::to_string(static_cast<int>(limits.max_duration_s)) + " s";
  if (limits.start)
    for (int k = 0; k < kArmJoints; ++k)
      if (std::abs(joints[k] - (*limits.start)[k]) > limits.start_tolerance_rad)
        return "invalid_trajectory:does not start at the current joint positions";
  const JointVector lo = robot.lower_limits(), hi = robot.upper_limits(), vmax = robot.max_velocities();
  for (int64_t i = 0; i < n; ++i)
    for (int k = 0; k < kArmJoints; ++k) {
      const double q = joints[i * kArmJoints + k];
      if (q < lo[k] - 1e-9 || q > hi[k] + 1e-9) return "joint_limits:joint" + std::to_string(k + 1);
      if (i > 0) {
        const double v = std::abs(q - joints[(i - 1) * kArmJoints + k]) / (times[i] - times[i - 1]);
        if (v > vmax[k] * limits.velocity_slack) return "velocity_limit:joint" + std::to_string(k + 1);
      }
    }
  return "";
}

JointVector joint_path_at(const double* times, const double* joints, int64_t n, double t) {
  const Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, kArmJoints, Eigen::RowMajor>> q(joints, n, kArmJoints);
  if (n == 1 || t <= times[0]) return q.row(0).transpose();
  if (t >= times[n - 1]) return q.row(n - 1).transpose();
  const int64_t i = std::upper_bound(times, times + n, t) - times;  // times[i - 1] <= t < times[i]
  const double a = (t - times[i - 1]) / (times[i] - times[i - 1]);
  return ((1 - a) * q.row(i - 1) + a * q.row(i)).transpose();
}

}  // namespace qte::robot

#include "robot/inverse_kinematics.hpp"

#include <algorithm>
#include <cmath>
#include <random>

namespace qte::robot {
namespace {

Eigen::Matrix<double, 6, 1> pose_error(const Eigen::Isometry3d& current, const Eigen::Isometry3d& target) {
  Eigen::Matrix<double, 6, 1> e;
  e.head<3>() = target.translation() - current.translation();
  const Eigen::AngleAxisd rotation(target.linear() * current.linear().transpose());
  e.tail<3>() = rotation.axis() * rotation.angle();
  return e;
}

// Clamps to the joint limits.
JointVector within_limits(JointVector q, const JointVector& lo, const JointVector& hi) {
  for (int k = 0; k < kArmJoints; ++k) q[k] = std::clamp(q[k], lo[k], hi[k]);
  return q;
}

}  // namespace

double position_error_m(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return (a.translation() - b.translation()).norm();
}

double angle_error_rad(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return Eigen::AngleAxisd(a.linear() * b.linear().transpose()).angle();
}

std::optional<JointVector> solve_ik(const RobotModel& robot, const Eigen::Isometry3d& target,
                                    const JointVector& start, const IkOptions& options) {
  const JointVector lo = robot.lower_limits(), hi = robot.upper_limits();
  std::mt19937_64 rng(options.seed);
  std::optional<JointVector> best;
  double best_distance = 1e18;
  for (int attempt = 0; attempt <= options.restarts; ++attempt) {
    JointVector q = start;
    if (attempt > 0) {
      // Restarts sample each joint within +-pi of the start (or its limits) so solutions
      // stay near the current configuration when one exists there.
      for (int k = 0; k < kArmJoints; ++k)
        q[k] = std::uniform_real_distribution<double>(std::max(lo[k], start[k] - M_PI),
                                                      std::min(hi[k], start[k] + M_PI))(rng);
    }
    q = within_limits(q, lo, hi);
    for (int it = 0; it < options.iterations; ++it) {
      const Eigen::Isometry3d pose = robot.tcp_pose(q);
      Eigen::Matrix<double, 6, 1> e = pose_error(pose, target);
      if (e.head<3>().norm() < options.position_tolerance_m &&
          e.tail<3>().norm() < options.angle_tolerance_rad) {
        const double distance = (q - start).norm();
        if (distance < best_distance) {
          best_distance = distance;
          best = q;
        }
        break;
      }
      // Damped least squares; damping grows with the error so far steps stay stable.
      const auto jacobian = robot.tcp_jacobian(q);
      const double lambda = 0.01 + 0.1 * e.norm();
      const Eigen::Matrix<double, 6, 6> jjt =
          jacobian * jacobian.transpose() + lambda * lambda * Eigen::Matrix<double, 6, 6>::Identity();
      JointVector dq = jacobian.transpose() * jjt.ldlt().solve(e);
      const double step = dq.cwiseAbs().maxCoeff();
      if (step > 0.3) dq *= 0.3 / step;
      q = within_limits(q + dq, lo, hi);
    }
    // The seed configuration converging is the nearest possible answer: stop early.
    if (best && attempt == 0) break;
    if (best && attempt >= 4 && best_distance < 0.5) break;
  }
  return best;
}

}  // namespace qte::robot

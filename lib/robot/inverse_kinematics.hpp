// Numerical inverse kinematics of the TCP: damped least squares with joint limits and seeded
// random restarts, returning the solution nearest the starting configuration.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <optional>

#include "robot/robot_model.hpp"

namespace qte::robot {

struct IkOptions {
  double position_tolerance_m = 0.0005;
  double angle_tolerance_rad = 0.004;  // 0.23 deg
  int iterations = 150;               // per attempt
  int restarts = 24;                  // random starting points after the seed configuration
  uint64_t seed = 0;
};

// Joint positions putting the TCP at `target` (robot base frame), or nothing when no attempt
// converged within the tolerances. Among converged attempts, the one closest to `start`.
std::optional<JointVector> solve_ik(const RobotModel& robot, const Eigen::Isometry3d& target,
                                    const JointVector& start, const IkOptions& options = {});

// Position and angle error between two poses.
double position_error_m(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b);
double angle_error_rad(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b);

}  // namespace qte::robot

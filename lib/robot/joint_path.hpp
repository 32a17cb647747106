// Joint paths as 'trajectory' records hold them: time-stamped waypoints of the 7 arm joints,
// followed piecewise-linearly. One home for what makes a path executable, shared by sim-step
// (which executes it) and xarm-export (which hands it to the real arm).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "robot/robot_model.hpp"

namespace qte::robot {

struct JointPathLimits {
  double max_duration_s = 60.0;
  const JointVector* start = nullptr;  // when set, the path must begin here...
  double start_tolerance_rad = 1e-3;   // ...within this
  double velocity_slack = 1.01;        // speeds up to this multiple of the joints' limits pass
};

// Why the path (n waypoints: time_s[n], joints[n * 7] in radians) cannot be executed, or ""
// when it can. Checked in this order, spelled as an observation's `failure`:
// invalid_trajectory:not_finite, invalid_trajectory:time_s must start at 0 and increase,
// invalid_trajectory:longer than N s, invalid_trajectory:does not start at the current joint
// positions, joint_limits:jointK, velocity_limit:jointK.
std::string joint_path_failure(const double* time_s, const double* joints, int64_t n, const RobotModel& robot,
                               const JointPathLimits& limits = {});

// The path's joints at time t (clamped to its ends): linear between waypoints.
JointVector joint_path_at(const double* time_s, const double* joints, int64_t n, double t);

}  // namespace qte::robot

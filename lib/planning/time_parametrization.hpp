// Joint paths to timed trajectories: each segment between waypoints follows a trapezoidal
// velocity profile (stopping at the waypoint) limited by the slowest joint's velocity and
// acceleration, sampled at a fixed period.
#pragma once

#include <vector>

#include "robot/robot_model.hpp"

namespace qte::planning {

struct TimedPath {
  std::vector<double> time_s;                    // from 0, increasing
  std::vector<robot::JointVector> joint_positions;  // one per time
};

TimedPath time_parametrize(const std::vector<robot::JointVector>& waypoints,
                           const robot::JointVector& max_velocity,
                           const robot::JointVector& max_acceleration, double sample_period_s);

}  // namespace qte::planning

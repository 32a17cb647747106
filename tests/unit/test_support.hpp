// Shared by the unit tests: the robot model, loaded once per test binary.
#pragma once

#include "robot/robot_model.hpp"

namespace qte::test_support {

inline const robot::RobotModel& xarm() {
  static const robot::RobotModel robot = robot::RobotModel::xarm7();
  return robot;
}

}  // namespace qte::test_support

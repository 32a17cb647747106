// Shared by the unit tests: the robot model, loaded once per test binary; scratch directories.
#pragma once

#include <stdlib.h>

#include <filesystem>
#include <string>

#include "robot/robot_model.hpp"

namespace qte::test_support {

inline const robot::RobotModel& xarm() {
  static const robot::RobotModel robot = robot::RobotModel::xarm7();
  return robot;
}

// A new empty directory under the system's temporary directory (left for the OS to clean).
inline std::string temp_dir(const std::string& name) {
  std::string pattern = (std::filesystem::temp_directory_path() / ("qte_" + name + "_XXXXXX")).string();
  return ::mkdtemp(pattern.data());
}

}  // namespace qte::test_support

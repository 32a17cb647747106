// Planned joint paths in the form a real xArm 7 takes them: joint angles in degrees at a fixed
// control rate (its servo mode, set_servo_angle_j) and the gripper in the xArm gripper's units
// (0 closed .. 850 open), checked against the joint limits and speeds before anything is written.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "robot/joint_path.hpp"

namespace qte::robot {

constexpr double kXarmGripperOpenUnits = 850.0;  // the xArm gripper's position at its widest

// When the rows of a motion come (xarm-export's and robot-step's --rate and --settle).
struct XarmTiming {
  double rate_hz = 100;   // the control rate (the xArm's servo mode takes up to 250 Hz)
  double settle_s = 0.5;  // after a motion's end, the gripper command's row
  // The options' ranges: the gripper's row needs a time of its own after the motion's last.
  static constexpr double kMinRate_hz = 1, kMaxRate_hz = 1000, kMinSettle_s = 0.01, kMaxSettle_s = 10;
};

struct XarmRow {
  double time_s = 0;
  JointVector degrees = JointVector::Zero();
  int gripper = 0;  // 0..850
};

// The path sampled every 1/rate_hz s (and at its end), linearly between waypoints as sim-step
// follows it. The gripper holds `gripper_before_m` during the motion; one more row, `settle_s`
// after the end, commands `gripper_after_m`. Throws Error with joint_path_failure()'s reason,
// checked on the waypoints and again on the rows.
std::vector<XarmRow> xarm_rows(const double* time_s, const double* joints, int64_t n, double gripper_before_m,
                               double gripper_after_m, const RobotModel& robot, double rate_hz, double settle_s);

// The motions of an episode in order, as xarm_rows() of each: during a motion the gripper holds
// what the last observation said (open before any observation), or what the motion before it
// commanded; after the motion it goes to the motion's own command.
class XarmEpisode {
 public:
  XarmEpisode(const RobotModel& robot, double rate_hz, double settle_s)
      : robot_(robot), rate_hz_(rate_hz), settle_s_(settle_s) {}
  void observe_gripper(double opening_m) { gripper_m_ = opening_m; }
  std::vector<XarmRow> motion(const double* time_s, const double* joints, int64_t n, bool gripper_open_after);

 private:
  const RobotModel& robot_;
  double rate_hz_, settle_s_;
  std::optional<double> gripper_m_;  // none: nothing observed yet, open
};

// CSV: a comment header saying what the columns are, then time_s,j1..j7 (degrees),gripper.
std::string xarm_csv(const std::vector<XarmRow>& rows, const std::string& comment);

// Metres between the fingers to gripper units and back.
int xarm_gripper_units(double opening_m, const RobotModel& robot);

}  // namespace qte::robot

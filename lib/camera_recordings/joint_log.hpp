// A recorded demonstration's robot side: the arm driver's joint log with time stamps and the
// camera's frame times on the same clock. Each frame's robot state is the log's at the frame's
// time, its joint velocities the log's finite difference there: keyframes are where the arm
// stands still, so a log at the camera's rate or faster is needed to see it stop.
#pragma once

#include <string>
#include <vector>

#include "camera_recordings/camera_recordings.hpp"

namespace qte::camera_recordings {

// One row of a CSV file of numbers and the line it is on (from 1).
struct NumberRow {
  int line = 0;
  std::vector<double> values;
};

// The most read of a CSV of numbers (a joint log, frame times): a line, and the whole file (a
// joint log of 1 kHz for hours fits).
constexpr std::size_t kNumberRowLimitBytes = 4096;
constexpr uint64_t kNumberFileLimitBytes = uint64_t(1) << 30;

// The rows of a CSV file of numbers, by the rules of every table obs-pack reads: a first line
// with no number in it is a header, empty lines and lines starting with '#' are skipped, every
// cell must be a finite number (nan and inf read as numbers: a row of them is data, and
// refused) and a row must have one of `column_counts` cells. Throws Error naming the file, line
// and column, with `columns` (what the columns are); a file without rows names `rows` (what one
// row is).
std::vector<NumberRow> read_number_rows(const std::string& path, const std::vector<std::size_t>& column_counts,
                                        const std::string& columns, const std::string& rows);

struct JointLog {
  std::string path;
  std::vector<double> times_s;     // strictly increasing
  std::vector<RobotState> states;  // one per time; gripper_open set when the log has the column
};

// time_s, 7 joint angles (rad), the gripper opening (m) and optionally whether the gripper is
// open (1) or closed (0): a closed gripper holding an object stands as wide as the object.
// At least two rows, times strictly increasing, joints within the robot's limits, the opening
// within 0..the fingers' reach; an Error naming the file and line otherwise.
JointLog read_joint_log(const std::string& path, const robot::RobotModel& robot);

struct FrameTimes {
  std::string path;
  std::vector<double> times_s;  // strictly increasing
  std::vector<int> lines;       // the line of each time, for messages
};

// One time (s) per row, the time each frame was taken on the joint log's clock.
FrameTimes read_frame_times(const std::string& path);

// The robot at `time_s` (within the log's span): joints and opening interpolated linearly
// between the rows around it (a row's own values at its time), the joint velocities the slope
// of the log over the row interval that ends at or contains `time_s` (the motion that led
// there; the first interval at the first row), the gripper's open state the last row's at or
// before `time_s`.
RobotState state_at(const JointLog& log, double time_s);

// state_at every frame time; Error naming the frame times' file and line when a time is
// outside the log's span.
std::vector<RobotState> states_at(const JointLog& log, const FrameTimes& frames);

}  // namespace qte::camera_recordings

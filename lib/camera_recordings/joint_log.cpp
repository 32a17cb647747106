#include "camera_recordings/joint_log.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include "common/bounded_file.hpp"
#include "common/error.hpp"

namespace qte::camera_recordings {

namespace {

// One CSV cell: a finite number, a number that is not finite (nan, inf, 1e999) or not a number.
enum class Cell { finite, not_finite, not_a_number };

Cell read_cell(const std::string& text, double& value) {
  const char* s = text.c_str();
  char* end = nullptr;
  value = std::strtod(s, &end);
  while (end && (*end == ' ' || *end == '\t' || *end == '\r')) ++end;
  if (end == s || *end != '\0') return Cell::not_a_number;
  return std::isfinite(value) ? Cell::finite : Cell::not_finite;
}

// Cells between commas: "a,,b," is four cells, the second and last empty.
std::vector<std::string> cells_of(const std::string& line) {
  std::vector<std::string> cells(1);
  for (char c : line) {
    if (c == ',') cells.emplace_back();
    else cells.back() += c;
  }
  return cells;
}

std::string shown(std::string cell) {
  while (!cell.empty() && (cell.back() == '\r' || cell.back() == ' ')) cell.pop_back();
  if (cell.empty()) return "empty";
  if (cell.size() > 32) return "a " + std::to_string(cell.size()) + "-character text";
  for (char& c : cell)
    if (c < 0x20 || c > 0x7e) c = '?';
  return "'" + cell + "'";
}

std::string seconds(double t) {
  char text[32];
  std::snprintf(text, sizeof text, "%.9g s", t);
  return text;
}

std::string where(const std::string& path, const NumberRow& row) {
  return path + ": line " + std::to_string(row.line) + ": ";
}

// Joint angles from values[first..first+7), checked against the robot's limits.
robot::JointVector joints_of(const std::string& path, const NumberRow& row, std::size_t first,
                             const robot::RobotModel& robot) {
  const robot::JointVector lo = robot.lower_limits(), hi = robot.upper_limits();
  robot::JointVector joints;
  for (int k = 0; k < robot::kArmJoints; ++k) {
    const double q = row.values[first + k];
    if (q < lo[k] - 1e-6 || q > hi[k] + 1e-6)
      throw Error(where(path, row) + "joint " + std::to_string(k + 1) + " at " + std::to_string(q) +
                  " rad is outside its limits (" + std::to_string(lo[k]) + ", " + std::to_string(hi[k]) +
                  "); are the angles in degrees?");
    joints[k] = q;
  }
  return joints;
}

double opening_of(const std::string& path, const NumberRow& row, std::size_t column, const robot::RobotModel& robot) {
  const double opening = row.values[column];
  if (!(opening >= 0 && opening <= robot.max_finger_opening_m() + 1e-6))
    throw Error(where(path, row) + "gripper opening " + std::to_string(opening) + " m is outside 0.." +
                std::to_string(robot.max_finger_opening_m()));
  return opening;
}

// Times of rows, each after the one before: a log or frames out of order are refused.
void check_increasing(const std::string& path, const std::vector<NumberRow>& rows, const std::string& what) {
  for (std::size_t i = 1; i < rows.size(); ++i)
    if (!(rows[i].values[0] > rows[i - 1].values[0]))
      throw Error(where(path, rows[i]) + what + " " + seconds(rows[i].values[0]) + " is not after line " +
                  std::to_string(rows[i - 1].line) + "'s " + seconds(rows[i - 1].values[0]) +
                  " (times must increase row by row)");
}

}  // namespace

std::vector<NumberRow> read_number_rows(const std::string& path, const std::vector<std::size_t>& column_counts,
                                        const std::string& columns, const std::string& rows) {
  BoundedLines in(path, kNumberRowLimitBytes, kNumberFileLimitBytes, rows + " (" + columns + ")");
  std::string counts;
  for (std::size_t i = 0; i < column_counts.size(); ++i)
    counts += (i == 0 ? "" : i + 1 == column_counts.size() ? " or " : ", ") + std::to_string(column_counts[i]);
  std::vector<NumberRow> out;
  std::string line;
  while (in.next(line)) {
    const int number = in.line_number();
    if (line.empty() || line[0] == '#') continue;
    const std::vector<std::string> cells = cells_of(line);
    NumberRow row{number, std::vector<double>(cells.size())};
    std::vector<Cell> kinds(cells.size());
    bool any_number = false;
    for (std::size_t c = 0; c < cells.size(); ++c) {
      kinds[c] = read_cell(cells[c], row.values[c]);
      any_number = any_number || kinds[c] != Cell::not_a_number;
    }
    // A first line of names is a header; "nan" or "inf" reads as a number, so a row of them is data.
    if (number == 1 && !any_number) continue;
    for (std::size_t c = 0; c < cells.size(); ++c)
      if (kinds[c] != Cell::finite)
        throw Error(where(path, row) + "column " + std::to_string(c + 1) + " is " + shown(cells[c]) +
                    ", expected a finite number (" + columns + ")");
    if (std::find(column_counts.begin(), column_counts.end(), cells.size()) == column_counts.end())
      throw Error(where(path, row) + std::to_string(cells.size()) + " columns, expected " + counts + " (" + columns +
                  ")");
    out.push_back(std::move(row));
  }
  if (out.empty()) throw Error(path + ": no rows, expected " + rows + " (" + columns + ")");
  return out;
}

std::vector<RobotState> read_joint_csv(const std::string& path, const robot::RobotModel& robot) {
  const auto rows = read_number_rows(
      path, {7, 8}, "7 joint angles in radians, then optionally the gripper opening in metres", "one row per frame");
  std::vector<RobotState> states;
  for (const NumberRow& row : rows) {
    RobotState s;
    s.joints = joints_of(path, row, 0, robot);
    s.gripper_opening_m = row.values.size() == 8 ? opening_of(path, row, 7, robot) : robot.max_finger_opening_m();
    states.push_back(s);
  }
  return states;
}

JointLog read_joint_log(const std::string& path, const robot::RobotModel& robot) {
  const std::string columns =
      "time in seconds, 7 joint angles in radians, the gripper opening in metres, then optionally 1 for an open "
      "gripper, 0 for a closed one";
  const auto rows = read_number_rows(path, {9, 10}, columns, "one row per time stamp");
  if (rows.size() < 2)
    throw Error(path + ": one row, expected at least two (joint velocities are differences of rows)");
  check_increasing(path, rows, "time");
  JointLog log;
  log.path = path;
  for (const NumberRow& row : rows) {
    RobotState s;
    s.joints = joints_of(path, row, 1, robot);
    s.gripper_opening_m = opening_of(path, row, 8, robot);
    if (row.values.size() == 10) {
      if (row.values[9] != 0 && row.values[9] != 1)
        throw Error(where(path, row) + "column 10 is " + std::to_string(row.values[9]) +
                    ", expected 1 (gripper open) or 0 (closed)");
      s.gripper_open = row.values[9] == 1;
    }
    log.times_s.push_back(row.values[0]);
    log.states.push_back(s);
  }
  return log;
}

FrameTimes read_frame_times(const std::string& path) {
  const auto rows =
      read_number_rows(path, {1}, "the frame's time in seconds, on the joint log's clock", "one row per frame");
  check_increasing(path, rows, "frame time");
  FrameTimes frames;
  frames.path = path;
  for (const NumberRow& row : rows) {
    frames.times_s.push_back(row.values[0]);
    frames.lines.push_back(row.line);
  }
  return frames;
}

RobotState state_at(const JointLog& log, double time_s) {
  const std::vector<double>& t = log.times_s;
  if (t.size() < 2 || !(time_s >= t.front() && time_s <= t.back()))
    throw Error(log.path + ": time " + seconds(time_s) + " is outside the log's " + seconds(t.front()) + " to " +
                seconds(t.back()));
  // The interval (t[j-1], t[j]] holding time_s; the first one at the first row.
  const std::size_t j = std::max<std::size_t>(1, std::lower_bound(t.begin(), t.end(), time_s) - t.begin());
  const RobotState &a = log.states[j - 1], &b = log.states[j];
  RobotState s;
  if (time_s == t[j]) {
    s = b;
  } else if (time_s == t[j - 1]) {
    s = a;
  } else {
    const double f = (time_s - t[j - 1]) / (t[j] - t[j - 1]);
    s.joints = a.joints + f * (b.joints - a.joints);
    s.gripper_opening_m = a.gripper_opening_m + f * (b.gripper_opening_m - a.gripper_opening_m);
    s.gripper_open = a.gripper_open;
  }
  s.joint_velocities_rad_s = (b.joints - a.joints) / (t[j] - t[j - 1]);
  return s;
}

std::vector<RobotState> states_at(const JointLog& log, const FrameTimes& frames) {
  std::vector<RobotState> states;
  for (std::size_t i = 0; i < frames.times_s.size(); ++i) {
    const double time = frames.times_s[i];
    if (!(time >= log.times_s.front() && time <= log.times_s.back()))
      throw Error(frames.path + ": line " + std::to_string(frames.lines[i]) + ": frame time " + seconds(time) +
                  " is outside the joint log " + log.path + " (" + seconds(log.times_s.front()) + " to " +
                  seconds(log.times_s.back()) + ")");
    states.push_back(state_at(log, time));
  }
  return states;
}

}  // namespace qte::camera_recordings

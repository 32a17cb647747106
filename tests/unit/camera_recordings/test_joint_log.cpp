// Recorded demonstrations: the time-stamped joint log and the frame times (strict CSV, times
// increasing), each frame's state interpolated from the log with the log's slope for velocity,
// and a recording packed as one demonstration (steps counted by keyframes, the last frame
// terminal with its success).
#include <gtest/gtest.h>

#include <cstdio>
#include <opencv2/imgcodecs.hpp>
#include <string>

#include "camera_recordings/joint_log.hpp"
#include "camera_recordings/recording.hpp"
#include "common/error.hpp"
#include "test_support.hpp"

using namespace qte;
using namespace qte::camera_recordings;

namespace {

std::string file_with(const std::string& text) {
  static int n = 0;
  const std::string path = test_support::temp_dir("joint_log") + "/file" + std::to_string(n++) + ".csv";
  FILE* f = std::fopen(path.c_str(), "w");
  std::fputs(text.c_str(), f);
  std::fclose(f);
  return path;
}

template <typename Read>
std::string error_of(const Read& read) {
  try {
    read();
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos);
    return e.what();
  }
  return "";
}

std::string log_error(const std::string& text) {
  const std::string path = file_with(text);
  return error_of([&] { read_joint_log(path, test_support::xarm()); });
}

// Joint 1 moves 0.1 rad per row, 0.1 s apart (1 rad/s), and stands still from t = 0.3.
const char* kLog =
    "time_s,j1,j2,j3,j4,j5,j6,j7,gripper_m,open\n"
    "10.0,0.0,0,0,0,0,0,0,0.085,1\n"
    "10.1,0.1,0,0,0,0,0,0,0.085,1\n"
    "10.2,0.2,0,0,0,0,0,0,0.060,0\n"
    "10.3,0.3,0,0,0,0,0,0,0.050,0\n"
    "10.4,0.3,0,0,0,0,0,0,0.050,0\n";

}  // namespace

TEST(JointLog, RowsOfTimeJointsAndGripper) {
  const JointLog log = read_joint_log(file_with(kLog), test_support::xarm());
  ASSERT_EQ(log.times_s.size(), 5u);
  EXPECT_DOUBLE_EQ(log.times_s[2], 10.2);
  EXPECT_DOUBLE_EQ(log.states[2].joints[0], 0.2);
  EXPECT_DOUBLE_EQ(log.states[2].gripper_opening_m, 0.06);
  EXPECT_EQ(log.states[1].gripper_open, true);
  EXPECT_EQ(log.states[2].gripper_open, false);
  // Without the tenth column the gripper state is left to the opening.
  const JointLog nine = read_joint_log(file_with("0,0,0,0,0,0,0,0,0.07\n1,0,0,0,0,0,0,0,0.01\n"), test_support::xarm());
  EXPECT_FALSE(nine.states[0].gripper_open.has_value());
}

TEST(JointLog, BadLogsAreNamedByLine) {
  const std::string backwards = file_with("0,0,0,0,0,0,0,0,0.08\n0.2,0,0,0,0,0,0,0,0.08\n0.2,0,0,0,0,0,0,0,0.08\n");
  EXPECT_EQ(error_of([&] { read_joint_log(backwards, test_support::xarm()); }),
            backwards + ": line 3: time 0.2 s is not after line 2's 0.2 s (times must increase row by row)");
  EXPECT_NE(log_error("0,0,0,0,0,0,0,0\n1,0,0,0,0,0,0,0\n").find(": line 1: 8 columns, expected 9 or 10 (time in seconds"),
            std::string::npos);
  EXPECT_NE(log_error("0,0,0,0,0,0,0,0,0.08,0.5\n1,0,0,0,0,0,0,0,0.08,1\n")
                .find(": line 1: column 10 is 0.500000, expected 1 (gripper open) or 0 (closed)"),
            std::string::npos);
  EXPECT_NE(log_error("0,0,0,0,0,0,0,0,0.08\n").find(": one row, expected at least two"), std::string::npos);
  EXPECT_NE(log_error("0,0,0,0,0,0,0,0,0.08\n1,0,0,0,0,0,90,0,0.08\n").find(": line 2: joint 6 at 90.000000 rad"),
            std::string::npos);
  EXPECT_NE(log_error("0,0,0,0,0,0,0,0,0.08\n1,0,0,0,0,0,0,0,0.5\n").find(": line 2: gripper opening 0.500000 m"),
            std::string::npos);
  EXPECT_NE(log_error("0,0,0,0,0,nan,0,0,0.08\n").find(": line 1: column 6 is 'nan', expected a finite number"),
            std::string::npos);
  EXPECT_NE(log_error("time,j1,j2,j3,j4,j5,j6,j7,gripper\n").find(": no rows, expected one row per time stamp"),
            std::string::npos);
}

TEST(JointLog, FrameTimesIncrease) {
  const FrameTimes frames = read_frame_times(file_with("time_s\n1.5\n# a comment\n1.75\n"));
  ASSERT_EQ(frames.times_s.size(), 2u);
  EXPECT_DOUBLE_EQ(frames.times_s[1], 1.75);
  EXPECT_EQ(frames.lines[1], 4);
  const std::string same = file_with("1\n1\n");
  EXPECT_EQ(error_of([&] { read_frame_times(same); }),
            same + ": line 2: frame time 1 s is not after line 1's 1 s (times must increase row by row)");
  const std::string two = file_with("1,2\n");
  EXPECT_NE(error_of([&] { read_frame_times(two); }).find(": line 1: 2 columns, expected 1 (the frame's time in seconds"),
            std::string::npos);
}

// A frame at a row's time has the row's values exactly and the slope of the interval that led
// there; between rows the values are interpolated, the gripper state held from the row before.
TEST(JointLog, StatesAtFrameTimes) {
  const JointLog log = read_joint_log(file_with(kLog), test_support::xarm());
  const RobotState first = state_at(log, 10.0);
  EXPECT_EQ(first.joints[0], 0.0);
  EXPECT_NEAR(first.joint_velocities_rad_s[0], 1.0, 1e-9);  // the first interval's
  const RobotState at_row = state_at(log, 10.2);
  EXPECT_EQ(at_row.joints[0], 0.2);
  EXPECT_EQ(at_row.gripper_opening_m, 0.06);
  EXPECT_EQ(at_row.gripper_open, false);
  EXPECT_NEAR(at_row.joint_velocities_rad_s[0], 1.0, 1e-9);
  const RobotState between = state_at(log, 10.15);
  EXPECT_NEAR(between.joints[0], 0.15, 1e-12);
  EXPECT_NEAR(between.gripper_opening_m, 0.0725, 1e-12);
  EXPECT_EQ(between.gripper_open, true);  // the row at 10.1's
  EXPECT_NEAR(between.joint_velocities_rad_s[0], 1.0, 1e-9);
  const RobotState arrived = state_at(log, 10.3);
  EXPECT_NEAR(arrived.joint_velocities_rad_s[0], 1.0, 1e-9);  // the interval that led there
  const RobotState resting = state_at(log, 10.35);
  EXPECT_EQ(resting.joint_velocities_rad_s[0], 0.0);
  EXPECT_EQ(state_at(log, 10.4).joint_velocities_rad_s[0], 0.0);
  EXPECT_THROW(state_at(log, 10.41), Error);
  EXPECT_THROW(state_at(log, 9.99), Error);

  const std::string times = file_with("10.1\n10.45\n");
  EXPECT_EQ(error_of([&] { states_at(log, read_frame_times(times)); }),
            times + ": line 2: frame time 10.45 s is outside the joint log " + log.path + " (10 s to 10.4 s)");
  EXPECT_EQ(states_at(log, read_frame_times(file_with("10.1\n10.3\n"))).size(), 2u);
}

// Moving, a stop, moving on with the gripper closed, arriving: keyframes at the stop, the close
// and the end; a frame's step is the motion it belongs to, as demo-record numbers them.
TEST(JointLog, DemonstrationStepsCountKeyframes) {
  std::vector<RobotState> states(14);
  for (std::size_t i = 0; i < states.size(); ++i) {
    states[i].joint_velocities_rad_s.setConstant(i == 0 || i == 5 || i == 13 ? 0.0 : 0.5);
    states[i].gripper_open = i < 9;
  }
  const std::vector<int> steps = demonstration_steps(states, test_support::xarm());
  const std::vector<int> expected = {0, 1, 1, 1, 1, 1, 2, 2, 2, 2, 3, 3, 3, 3};  // keyframes 5, 9, 13
  EXPECT_EQ(steps, expected);
}

// Three frames packed as one demonstration: frames 0..2, velocities from the states, time since
// the first frame, the last terminal with the success and its reward; a failed one ends with 0.
TEST(JointLog, RecordingPackedAsOneDemonstration) {
  const std::string dir = test_support::temp_dir("demonstration");
  for (int i = 0; i < 3; ++i) {
    cv::imwrite(dir + "/rgb_" + std::to_string(i) + ".png", cv::Mat(8, 8, CV_8UC3, cv::Scalar(10, 20, 30)));
    cv::imwrite(dir + "/depth_" + std::to_string(i) + ".png", cv::Mat(8, 8, CV_16UC1, cv::Scalar(1000)));
  }
  Recording recording;
  recording.rgb_pattern = dir + "/rgb_%d.png";
  recording.depth_pattern = dir + "/depth_%d.png";
  recording.task = "reach_target";
  recording.camera.intrinsics = intrinsics_from_values({8, 8, 4, 4}, "intrinsics");
  recording.camera.camera_to_world = camera_pose_from_values({0, 0, 1.75, 1, 0, 0, 0}, "camera-pose");
  recording.joints_path = "frames.csv";
  for (int i = 0; i < 3; ++i) {
    RobotState state;
    state.joints(0) = 0.1 * i;
    state.joint_velocities_rad_s(0) = i == 2 ? 0.0 : 2.0;
    recording.states.push_back(state);
    recording.times_s.push_back(0.05 * i);
  }
  recording.demonstration_success = true;
  std::vector<stream::Record> records;
  const auto keep = [&](const stream::Record& r) { records.push_back(r); };
  EXPECT_EQ(pack_recording(recording, test_support::xarm(), keep).written, 3);
  ASSERT_EQ(records.size(), 3u);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(records[i].scalar<int32_t>("frame"), i);
    EXPECT_EQ(records[i].scalar<int32_t>("step"), i == 0 ? 0 : 1);
    EXPECT_DOUBLE_EQ(records[i].scalar<double>("time_s"), 0.05 * i);
    EXPECT_EQ(records[i].array<double>("joint_velocities")[0], i == 2 ? 0.0 : 2.0);
    EXPECT_EQ(records[i].scalar<uint8_t>("terminal"), i == 2);
    EXPECT_EQ(records[i].scalar<uint8_t>("success"), i == 2);
    EXPECT_EQ(records[i].scalar<float>("reward"), i == 2 ? 100.0f : 0.0f);
  }
  records.clear();
  recording.demonstration_success = false;
  pack_recording(recording, test_support::xarm(), keep);
  ASSERT_EQ(records.size(), 3u);
  EXPECT_EQ(records[2].scalar<uint8_t>("terminal"), 1);
  EXPECT_EQ(records[2].scalar<uint8_t>("success"), 0);
  EXPECT_EQ(records[2].scalar<float>("reward"), 0.0f);

  recording.count = 4;  // more frames than states
  EXPECT_NE(error_of([&] { pack_recording(recording, test_support::xarm(), keep); })
                .find("frames.csv: 3 rows for a demonstration of 4 frames"),
            std::string::npos);
  recording.count = 1;
  EXPECT_NE(error_of([&] { pack_recording(recording, test_support::xarm(), keep); })
                .find("a demonstration of 1 frame, expected at least two"),
            std::string::npos);
}

// A joint log and frame times give a recording its states, its frames' times from the first and
// its count (one frame per time, unless a count was set).
TEST(JointLog, AddedToARecording) {
  const JointLog log = read_joint_log(file_with(kLog), test_support::xarm());
  Recording recording;
  add_joint_log(recording, log, read_frame_times(file_with("10.1\n10.25\n10.4\n")));
  EXPECT_EQ(recording.count, 3);
  ASSERT_EQ(recording.states.size(), 3u);
  EXPECT_NEAR(recording.times_s[1], 0.15, 1e-12);
  EXPECT_NEAR(recording.states[1].joints[0], 0.25, 1e-12);
  EXPECT_NE(recording.joints_path.find("file"), std::string::npos);  // the frame times name the rows
  recording.count = 2;
  add_joint_log(recording, log, read_frame_times(file_with("10.1\n10.25\n10.4\n")));
  EXPECT_EQ(recording.count, 2);
}

#include <gtest/gtest.h>

#include <vector>

#include "common/error.hpp"
#include "robot/robot_model.hpp"
#include "robot/xarm_export.hpp"
#include "test_support.hpp"

using namespace qte::robot;

namespace {
// A 1 s motion of the first joint by 0.1 rad: two waypoints.
std::vector<XarmRow> move(XarmEpisode& episode, bool open_after) {
  const std::vector<double> time_s = {0, 1};
  std::vector<double> joints(14, 0.0);
  joints[7] = 0.1;
  return episode.motion(time_s.data(), joints.data(), 2, open_after);
}
}  // namespace

// The gripper during a motion holds what the last observation said (open before any), or what
// the motion before commanded; the last row commands the motion's own gripper state.
TEST(XarmEpisode, TheGripperCarriesFromObservationsAndMotionsBefore) {
  const RobotModel& robot = qte::test_support::xarm();
  const int open = xarm_gripper_units(robot.max_finger_opening_m(), robot);
  XarmEpisode episode(robot, 10, 0.5);
  std::vector<XarmRow> rows = move(episode, false);
  ASSERT_EQ(rows.size(), 12u);  // 0 .. 1 s at 10 Hz, and the settle row
  EXPECT_EQ(rows.front().gripper, open);
  EXPECT_EQ(rows[10].gripper, open);
  EXPECT_EQ(rows.back().gripper, 0);
  EXPECT_DOUBLE_EQ(rows.back().time_s, 1.5);
  rows = move(episode, true);  // starts closed: the motion before closed it
  EXPECT_EQ(rows.front().gripper, 0);
  EXPECT_EQ(rows.back().gripper, open);
  episode.observe_gripper(0.03);  // an observation in between says where the fingers are
  rows = move(episode, true);
  EXPECT_EQ(rows.front().gripper, xarm_gripper_units(0.03, robot));
  EXPECT_GT(rows.front().gripper, 0);
  EXPECT_LT(rows.front().gripper, open);
}

// A motion the arm cannot follow is refused, and the gripper state stays what it was.
TEST(XarmEpisode, ARefusedMotionChangesNothing) {
  const RobotModel& robot = qte::test_support::xarm();
  XarmEpisode episode(robot, 10, 0.5);
  move(episode, false);  // closed after this one
  const std::vector<double> time_s = {0, 0.01};
  std::vector<double> joints(14, 0.0);
  joints[7] = 1.0;  // 100 rad/s
  EXPECT_THROW(episode.motion(time_s.data(), joints.data(), 2, true), qte::Error);
  EXPECT_EQ(move(episode, true).front().gripper, 0);
}

// A path ending a hair after a tick: the tick is dropped rather than written with the end's
// printed time, so the file's times increase row by row (the drivers refuse a repeated time).
TEST(XarmRows, NoTwoRowsShareAPrintedTime) {
  const RobotModel& robot = qte::test_support::xarm();
  const std::vector<double> time_s = {0, 1.00004};
  std::vector<double> joints(14, 0.0);
  joints[7] = 0.1;
  const std::vector<XarmRow> rows = xarm_rows(time_s.data(), joints.data(), 2, 0.085, 0.085, robot, 100, 0.5);
  const std::string csv = xarm_csv(rows, "");
  double previous = -1;
  std::size_t at = csv.find('\n') + 1;  // past the header
  while (at < csv.size()) {
    const double t = std::stod(csv.substr(at, csv.find(',', at) - at));
    EXPECT_GT(t, previous) << csv.substr(at, 40);
    previous = t;
    at = csv.find('\n', at) + 1;
  }
  EXPECT_DOUBLE_EQ(rows[rows.size() - 2].time_s, 1.00004);  // the path's own end is kept
}

#include <gtest/gtest.h>

#include <vector>

#include "common/error.hpp"
#include "robot_step/judge.hpp"
#include "robot_step/robot_world.hpp"
#include "robot_step/spool.hpp"
#include "test_support.hpp"

using namespace qte::robot_step;

// A path's times stretch by the largest ratio of a joint's speed to its allowed share of the
// limit, and never shrink.
TEST(TimeStretch, TheFastestJointSetsIt) {
  const qte::robot::RobotModel& robot = qte::test_support::xarm();
  const double limit = robot.max_velocities()[2];
  const std::vector<double> time_s = {0, 1, 2};
  std::vector<double> joints(21, 0.0);
  joints[7 + 2] = 0.5 * limit;          // half the limit in the first second
  joints[14 + 2] = 0.5 * limit + 2 * limit;  // twice the limit in the next
  EXPECT_DOUBLE_EQ(time_stretch(time_s.data(), joints.data(), 3, robot, 1.0), 2.0);
  EXPECT_DOUBLE_EQ(time_stretch(time_s.data(), joints.data(), 3, robot, 0.5), 4.0);
  joints[14 + 2] = joints[7 + 2];  // standing still: nothing to stretch
  EXPECT_DOUBLE_EQ(time_stretch(time_s.data(), joints.data(), 3, robot, 1.0), 1.0);
  EXPECT_DOUBLE_EQ(time_stretch(time_s.data(), joints.data(), 1, robot, 0.1), 1.0);
}

TEST(ParseDone, SevenAnglesAndAGripperPosition) {
  const MotionAnswer a = parse_done("0.5,-20,0,43,0,63,1.25,840\n", "x.done");
  EXPECT_TRUE(a.done);
  EXPECT_DOUBLE_EQ(a.degrees[1], -20);
  EXPECT_DOUBLE_EQ(a.degrees[6], 1.25);
  EXPECT_EQ(a.gripper, 840);
  EXPECT_THROW(parse_done("0,0,0,0,0,0,850\n", "x.done"), qte::Error);        // six angles
  EXPECT_THROW(parse_done("0,0,0,0,0,0,0,900\n", "x.done"), qte::Error);      // past open
  EXPECT_THROW(parse_done("0,0,0,0,0,0,0,850.5\n", "x.done"), qte::Error);    // not a position
  EXPECT_THROW(parse_done("0,0,0,nan,0,0,0,850\n", "x.done"), qte::Error);    // not finite
  EXPECT_THROW(parse_done("", "x.done"), qte::Error);
  try {
    parse_done("done\n", "spool/motion-1-000000.done");
    FAIL();
  } catch (const qte::Error& e) {
    EXPECT_NE(std::string(e.what()).find("spool/motion-1-000000.done"), std::string::npos) << e.what();
  }
}

TEST(ParseVerdict, SuccessFailureWithItsReasonOrContinue) {
  EXPECT_EQ(parse_verdict("success\n", "j").outcome, Outcome::success);
  EXPECT_EQ(parse_verdict("continue", "j").outcome, Outcome::go_on);
  const Verdict knocked = parse_verdict("failure knocked over the prism\r\n", "j");
  EXPECT_EQ(knocked.outcome, Outcome::failure);
  EXPECT_EQ(knocked.reason, "knocked over the prism");
  EXPECT_EQ(parse_verdict("failure", "j").reason, "judged_failure");
  EXPECT_THROW(parse_verdict("maybe", "j"), qte::Error);
  EXPECT_THROW(parse_verdict("", "j"), qte::Error);
  EXPECT_THROW(parse_verdict("successful", "j"), qte::Error);
}

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "common/error.hpp"
#include "robot/robot_model.hpp"

using namespace qte::robot;

TEST(RobotModel, LoadsTheXarm7Description) {
  const RobotModel robot = RobotModel::xarm7();
  EXPECT_NEAR(robot.max_finger_opening_m(), 0.085, 1e-9);  // 0-85 mm stroke
  EXPECT_NEAR(robot.lower_limits()[1], -118 * M_PI / 180, 1e-5);
  EXPECT_NEAR(robot.upper_limits()[3], 225 * M_PI / 180, 1e-5);
  EXPECT_NEAR(robot.max_velocities()[0], M_PI, 1e-5);  // 180 deg/s
  for (const auto& link : robot.links())
    if (link.name != "tcp") {
      EXPECT_FALSE(link.shapes.empty()) << link.name;
    }
}

TEST(RobotModel, ZeroPoseMatchesTheDhTable) {
  const RobotModel robot = RobotModel::xarm7();
  // All joints at zero: the arm stands up, the forearm offsets add along x; the flange
  // points down (z = 0.267 + 0.293 - 0.3425 - 0.097 = 0.1205) - well known for the xArm 7.
  const Eigen::Isometry3d flange = robot.link_poses(JointVector::Zero(), 0)[robot.link_index("link7")];
  EXPECT_NEAR(flange.translation().x(), 0.0525 + 0.0775 + 0.076, 1e-9);  // a4 + a5 + a7
  EXPECT_NEAR(flange.translation().y(), 0.0, 1e-9);
  EXPECT_NEAR(flange.translation().z(), 0.267 + 0.293 - 0.3425 - 0.097, 1e-9);
}

TEST(RobotModel, KnownConfigurations) {
  const RobotModel robot = RobotModel::xarm7();
  const int flange = robot.link_index("link7");
  // Joint 1 at +90 deg turns the zero pose about the base: x goes to y.
  JointVector q = JointVector::Zero();
  q[0] = M_PI / 2;
  Eigen::Vector3d p = robot.link_poses(q, 0)[flange].translation();
  EXPECT_NEAR(p.x(), 0.0, 1e-9);
  EXPECT_NEAR(p.y(), 0.206, 1e-9);
  EXPECT_NEAR(p.z(), 0.1205, 1e-9);
  // Joint 4 at +90 deg turns the hanging forearm forward: its 0.3425 m length, pointing down
  // at zero, now points along +x from the elbow (0.0525 forward, 0.267 + 0.293 up), and its
  // 0.0775 offset, along +x at zero, now points up.
  q = JointVector::Zero();
  q[3] = M_PI / 2;
  p = robot.link_poses(q, 0)[robot.link_index("link5")].translation();
  EXPECT_NEAR(p.z(), 0.267 + 0.293 + 0.0775, 1e-9);
  EXPECT_NEAR(p.x(), 0.0525 + 0.3425, 1e-9);
}

TEST(RobotModel, ReachBracketsTheDatasheets700mm) {
  const RobotModel robot = RobotModel::xarm7();
  // Largest distance from the shoulder (joint 2 axis) over random poses: the wrist centre
  // (joint 6) and the flange (joint 7) bracket the datasheet's 700 mm reach.
  std::mt19937 rng(1);
  double wrist = 0, flange = 0;
  const JointVector lo = robot.lower_limits(), hi = robot.upper_limits();
  const Eigen::Vector3d shoulder(0, 0, 0.267);
  for (int i = 0; i < 20000; ++i) {
    JointVector q;
    for (int k = 0; k < kArmJoints; ++k) q[k] = std::uniform_real_distribution<>(lo[k], hi[k])(rng);
    const auto poses = robot.link_poses(q, 0);
    wrist = std::max(wrist, (poses[robot.link_index("link6")].translation() - shoulder).norm());
    flange = std::max(flange, (poses[robot.link_index("link7")].translation() - shoulder).norm());
  }
  EXPECT_GT(wrist, 0.62);
  EXPECT_LT(wrist, 0.70);
  EXPECT_GT(flange, 0.70);
  EXPECT_LT(flange, 0.80);
}

TEST(RobotModel, JacobianMatchesFiniteDifferences) {
  const RobotModel robot = RobotModel::xarm7();
  JointVector q;
  q << 0.3, -0.5, 0.2, 1.1, -0.4, 0.9, 0.6;
  const auto jacobian = robot.tcp_jacobian(q);
  const double h = 1e-6;
  for (int k = 0; k < kArmJoints; ++k) {
    JointVector qp = q, qm = q;
    qp[k] += h;
    qm[k] -= h;
    const Eigen::Vector3d dp =
        (robot.tcp_pose(qp).translation() - robot.tcp_pose(qm).translation()) / (2 * h);
    EXPECT_LT((dp - jacobian.block<3, 1>(0, k)).norm(), 1e-6) << k;
    const Eigen::AngleAxisd dr(robot.tcp_pose(qp).linear() * robot.tcp_pose(qm).linear().transpose());
    EXPECT_LT((dr.axis() * dr.angle() / (2 * h) - jacobian.block<3, 1>(3, k)).norm(), 1e-5) << k;
  }
}

TEST(RobotModel, FingersOpenSymmetrically) {
  const RobotModel robot = RobotModel::xarm7();
  const auto poses = robot.link_poses(JointVector::Zero(), 0.06);
  const Eigen::Isometry3d tcp = poses[robot.tcp_link()];
  const Eigen::Vector3d l = tcp.inverse() * poses[robot.link_index("left_finger")].translation();
  const Eigen::Vector3d r = tcp.inverse() * poses[robot.link_index("right_finger")].translation();
  EXPECT_NEAR((l - r).norm(), 0.06, 1e-9);
  EXPECT_NEAR(l.y(), 0.03, 1e-9);
}

TEST(RobotModel, MissingOrBadFilesAreErrors) {
  EXPECT_THROW(RobotModel::load_urdf("/nonexistent.urdf"), qte::Error);
}

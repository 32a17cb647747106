// The robot's sphere cover: conservative for every primitive, modest in number, and its
// self-collision test agrees with the Bullet world's.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "common/error.hpp"
#include "planning/robot_spheres.hpp"
#include "world/world.hpp"
#include "test_support.hpp"

using namespace qte;
using namespace qte::planning;

namespace {

using test_support::xarm;

// Points on the surface of a primitive, in its own frame, about `step` apart.
std::vector<Eigen::Vector3d> surface_points(const robot::Shape& shape, double step) {
  std::vector<Eigen::Vector3d> points;
  auto steps = [&](double length) { return std::max(2, static_cast<int>(std::ceil(length / step)) + 1); };
  switch (shape.kind) {
    case robot::Shape::Kind::sphere: {
      const double r = shape.size.x();
      const int n = steps(M_PI * r);
      for (int i = 0; i < n; ++i)
        for (int j = 0; j < 2 * n; ++j) {
          const double polar = M_PI * i / (n - 1), azimuth = M_PI * j / n;
          points.emplace_back(r * std::sin(polar) * std::cos(azimuth), r * std::sin(polar) * std::sin(azimuth),
                              r * std::cos(polar));
        }
      break;
    }
    case robot::Shape::Kind::cylinder: {
      const double r = shape.size.x(), half = shape.size.y() / 2;
      const int around = steps(2 * M_PI * r), along = steps(2 * half), radial = steps(r);
      for (int a = 0; a < around; ++a) {
        const double angle = 2 * M_PI * a / around;
        const Eigen::Vector3d dir(std::cos(angle), std::sin(angle), 0);
        for (int k = 0; k < along; ++k)  // the side, rims included
          points.push_back(r * dir + Eigen::Vector3d(0, 0, -half + 2 * half * k / (along - 1)));
        for (int k = 0; k < radial; ++k)  // both caps
          for (double z : {-half, half}) points.push_back(r * k / (radial - 1) * dir + Eigen::Vector3d(0, 0, z));
      }
      break;
    }
    case robot::Shape::Kind::box: {
      const Eigen::Vector3d half = shape.size / 2;
      for (int axis = 0; axis < 3; ++axis) {
        const int u = (axis + 1) % 3, v = (axis + 2) % 3;
        const int nu = steps(shape.size[u]), nv = steps(shape.size[v]);
        for (int i = 0; i < nu; ++i)
          for (int j = 0; j < nv; ++j)
            for (double side : {-1.0, 1.0}) {
              Eigen::Vector3d p;
              p[axis] = side * half[axis];
              p[u] = -half[u] + shape.size[u] * i / (nu - 1);
              p[v] = -half[v] + shape.size[v] * j / (nv - 1);
              points.push_back(p);
            }
      }
      break;
    }
  }
  return points;
}

robot::JointVector ready_pose() {
  robot::JointVector q;
  q << 0, -0.35, 0, 0.75, 0, 1.1, 0;
  return q;
}

}  // namespace

TEST(RobotSpheres, EverySurfacePointOfEveryPrimitiveIsCovered) {
  const RobotSpheres spheres(xarm());
  // At a random pose in the world, so place() is checked too.
  std::mt19937 rng(5);
  const robot::JointVector lo = xarm().lower_limits(), hi = xarm().upper_limits();
  Eigen::Isometry3d world_from_base = Eigen::Isometry3d::Identity();
  world_from_base.translation() << -0.3, 0.1, 0.752;
  world_from_base.linear() = Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  for (int trial = 0; trial < 3; ++trial) {
    robot::JointVector q;
    for (int k = 0; k < robot::kArmJoints; ++k) q[k] = std::uniform_real_distribution<double>(lo[k], hi[k])(rng);
    const double opening = 0.04 * trial;
    std::vector<Sphere> placed;
    spheres.place(q, opening, world_from_base, placed);
    const auto link_poses = xarm().link_poses(q, opening);
    int checked = 0;
    for (int l = 0; l < static_cast<int>(xarm().links().size()); ++l)
      for (const auto& shape : xarm().links()[l].shapes)
        for (const Eigen::Vector3d& local : surface_points(shape, 0.002)) {
          const Eigen::Vector3d p = world_from_base * link_poses[l] * shape.link_from_shape * local;
          bool inside = false;
          for (const Sphere& s : placed)
            inside |= s.link == l && (p - s.centre).norm() <= s.radius_m + 1e-9;
          ++checked;
          ASSERT_TRUE(inside) << xarm().links()[l].name << " surface point " << local.transpose()
                              << " (shape frame) is in none of its spheres";
        }
    EXPECT_GT(checked, 10000);
  }
}

TEST(RobotSpheres, CountIsModestAndEveryLinkWithShapesHasSpheres) {
  const RobotSpheres spheres(xarm());
  EXPECT_LT(spheres.model().size(), 80u);
  for (int l = 0; l < static_cast<int>(xarm().links().size()); ++l) {
    int n = 0;
    for (const Sphere& s : spheres.model()) n += s.link == l;
    EXPECT_EQ(n > 0, !xarm().links()[l].shapes.empty()) << xarm().links()[l].name;
  }
  std::printf("xArm 7 + gripper: %zu spheres\n", spheres.model().size());
}

TEST(RobotSpheres, SelfCollisionAtTheReadyPoseAndWhenFolded) {
  const RobotSpheres spheres(xarm());
  std::vector<Sphere> placed;
  spheres.place(ready_pose(), 0.085, Eigen::Isometry3d::Identity(), placed);
  EXPECT_FALSE(spheres.self_collision(placed, 0.01));

  // Elbow folded far back, wrist bent back onto the forearm: the Bullet world reports a
  // link4-link7 collision here (tests/unit/simulator).
  robot::JointVector folded;
  folded << 0, -0.01, 0, 3.39, 0, 3.04, 0;
  spheres.place(folded, 0.085, Eigen::Isometry3d::Identity(), placed);
  EXPECT_TRUE(spheres.self_collision(placed, 0.01));
}

TEST(RobotSpheres, SelfCollisionIsConservativeAgainstTheBulletWorld) {
  // Every self-collision the Bullet world finds, the spheres (margin 0) find too: they cover
  // the primitives. The base stands high above the table, so only self-contacts are found.
  world::SceneLayout layout;
  layout.robot_base.z() = 3.0;
  world::World world(xarm(), layout);
  const RobotSpheres spheres(xarm());
  std::mt19937 rng(11);
  const robot::JointVector lo = xarm().lower_limits(), hi = xarm().upper_limits();
  std::vector<Sphere> placed;
  int bullet_collisions = 0, sphere_collisions = 0;
  for (int trial = 0; trial < 400; ++trial) {
    robot::JointVector q;
    for (int k = 0; k < robot::kArmJoints; ++k) q[k] = std::uniform_real_distribution<double>(lo[k], hi[k])(rng);
    const double opening = std::uniform_real_distribution<double>(0, 0.085)(rng);
    world.set_robot_state(q, opening);
    const std::string bullet = world.robot_collision();
    ASSERT_EQ(bullet.find("table"), std::string::npos);
    spheres.place(q, opening, world.robot_base_pose(), placed);
    const bool sphere = spheres.self_collision(placed);
    bullet_collisions += !bullet.empty();
    sphere_collisions += sphere;
    if (!bullet.empty()) {
      EXPECT_TRUE(sphere) << bullet << " at q = " << q.transpose();
    }
  }
  EXPECT_GT(bullet_collisions, 0);  // the test saw some
  std::printf("random poses: %d Bullet self-collisions, %d sphere self-collisions of 400\n", bullet_collisions,
              sphere_collisions);
}

TEST(RobotSpheres, UnplacedSpheresAreAnError) {
  const RobotSpheres spheres(xarm());
  EXPECT_THROW(spheres.self_collision({}), Error);
}

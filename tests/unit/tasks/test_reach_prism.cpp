// reach_prism: what the scene holds (three small yellow objects of one height, far enough
// apart, each within one depth-0 voxel's width), when it is solved, and that a seed decides it.
#include <gtest/gtest.h>

#include "task_scene.hpp"

using namespace qte;

namespace {

struct Scene : test_support::TaskScene {
  explicit Scene(uint64_t seed) : TaskScene("reach_prism", seed, 0) {}
};

const char* const kObjects[] = {"prism", "triangular_prism", "cube"};

}  // namespace

TEST(ReachPrism, ThreeLookalikesApartOnTheTable) {
  for (uint64_t seed = 0; seed < 20; ++seed) {
    Scene scene(seed);
    const double table = scene.world.layout().table_height_m;
    for (const char* a : kObjects) {
      const Eigen::Vector3d p = scene.pose(a).translation();
      EXPECT_NEAR(p.z(), table + 0.015, 1e-6) << a;  // one height: 3 cm, standing on the table (Bullet: floats)
      EXPECT_GE(p.x(), 0.0);
      EXPECT_LE(p.x(), 0.3);
      EXPECT_LE(std::abs(p.y()), 0.25);
      for (const char* b : kObjects)
        if (a != b) EXPECT_GE((p - scene.pose(b).translation()).head<2>().norm(), 0.1) << a << " " << b;
    }
  }
}

TEST(ReachPrism, SuccessIsTheGripperAboveThePentagonalPrismOnly) {
  Scene scene(3);
  const auto expert = scene.task->expert_waypoints(scene.world);
  ASSERT_EQ(expert.size(), 1u);
  const Eigen::Vector3d top = scene.pose("prism").translation() + Eigen::Vector3d(0, 0, 0.015);
  EXPECT_NEAR((expert[0].tcp_pose.translation() - top).norm(), 0.02, 1e-9);

  auto reach = [&](const Eigen::Vector3d& at) {
    Eigen::Isometry3d tcp = expert[0].tcp_pose;
    tcp.translation() = at;
    scene.world.set_robot_state(test_support::ik_world(scene.world, tcp), 0.085);
    return scene.task->success(scene.world);
  };
  EXPECT_TRUE(reach(expert[0].tcp_pose.translation()));
  EXPECT_TRUE(reach(expert[0].tcp_pose.translation() + Eigen::Vector3d(0.015, 0.015, 0)));  // 2.1 cm off
  EXPECT_FALSE(reach(expert[0].tcp_pose.translation() + Eigen::Vector3d(0.02, 0.02, 0)));   // 2.8 cm off
  // Above a lookalike: not the prism.
  for (const char* other : {"triangular_prism", "cube"})
    EXPECT_FALSE(reach(scene.pose(other).translation() + Eigen::Vector3d(0, 0, 0.035))) << other;
  // Too high above the right one.
  EXPECT_FALSE(reach(expert[0].tcp_pose.translation() + Eigen::Vector3d(0, 0, 0.03)));
}

TEST(ReachPrism, ASeedDecidesTheScene) {
  Scene a(11), b(11), c(12);
  for (const char* name : kObjects) {
    EXPECT_TRUE(a.pose(name).isApprox(b.pose(name), 0)) << name;
    EXPECT_FALSE(a.pose(name).isApprox(c.pose(name), 1e-6)) << name;
  }
}

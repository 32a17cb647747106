// stack_blocks: eight blocks and the plane apart on the table, colours and stack height from
// the variation; success only for the asked number of target blocks stacked on the plane with
// nothing held (a stack one short, a distractor in it, blocks side by side, a block still held:
// no); a seed decides the scene.
#include <gtest/gtest.h>

#include "task_scene.hpp"

using namespace qte;

namespace {

constexpr double kBlock = 0.05;

struct Scene : test_support::TaskScene {
  Scene(uint64_t seed, int variation) : TaskScene("stack_blocks", seed, variation) {}
  Eigen::Vector3d plane() const { return pose("target_plane").translation(); }
  // Grasped square to its faces, placed square to the world (as the expert does).
  void place(const std::string& name, const Eigen::Vector3d& to, bool release = true) {
    const Eigen::Vector3d x_axis = pose(name).linear().col(0);
    TaskScene::place(name, std::remainder(std::atan2(x_axis.y(), x_axis.x()), M_PI / 2), to, 0, release);
  }
  Eigen::Vector3d level(int k) const {
    return plane() + Eigen::Vector3d(0, 0, kBlock / 2 + k * kBlock - 0.001);  // the plane's centre is 1 mm up
  }
};

}  // namespace

TEST(StackBlocks, EightBlocksAndThePlaneApartOnTheTable) {
  const char* const names[] = {"target1", "target2", "target3", "target4", "distractor1",
                               "distractor2", "distractor3", "distractor4", "target_plane"};
  for (uint64_t seed = 0; seed < 30; ++seed) {
    Scene scene(seed, static_cast<int>(seed % 60));
    for (const char* a : names) {
      const Eigen::Vector3d p = scene.pose(a).translation();
      EXPECT_GE(p.x(), 0.0);
      EXPECT_LE(p.x(), 0.3);
      EXPECT_LE(std::abs(p.y()), 0.25);
      for (const char* b : names)
        if (a != b) EXPECT_GE((p - scene.pose(b).translation()).head<2>().norm(), 0.1 - 1e-6) << a << " " << b;
    }
    const auto colour = [&](const char* name) { return scene.world.object_spec(scene.world.object_id(name)).appearance.colour; };
    EXPECT_TRUE(colour("target1").isApprox(colour("target4")));
    EXPECT_TRUE(colour("distractor1").isApprox(colour("distractor4")));
    EXPECT_FALSE(colour("target1").isApprox(colour("distractor1")));
  }
}

TEST(StackBlocks, TheVariationNamesColourAndHeight) {
  const auto task = tasks::make_task("stack_blocks");
  EXPECT_EQ(task->variation_count(), 60);
  EXPECT_EQ(task->description(0), "stack 2 red blocks");
  EXPECT_EQ(task->description(5), "stack 4 maroon blocks");
  EXPECT_EQ(task->description(59), "stack 4 white blocks");
  EXPECT_EQ(task->episode_length(), 30);
  EXPECT_EQ(tasks::make_task("reach_target")->episode_length(), 10);
  // The expert: six next-best poses a block, none after the last release, within the episode.
  Scene scene(3, 2);  // 4 red blocks
  EXPECT_EQ(scene.task->expert_waypoints(scene.world).size(), 23u);
}

TEST(StackBlocks, SuccessIsTheAskedStackOnThePlaneWithNothingHeld) {
  Scene scene(5, 1);  // stack 3
  EXPECT_FALSE(scene.task->success(scene.world));
  scene.place("target1", scene.level(0));
  scene.place("target2", scene.level(1));
  EXPECT_FALSE(scene.task->success(scene.world));  // one short
  scene.place("target3", scene.level(2), /*release=*/false);
  EXPECT_FALSE(scene.task->success(scene.world));  // the third still held
  scene.world.open_gripper();
  scene.world.settle(0.5);
  EXPECT_NEAR(scene.pose("target3").translation().z(), scene.world.layout().table_height_m + 2.5 * kBlock, 0.005);
  EXPECT_TRUE(scene.task->success(scene.world));
  scene.place("target4", scene.level(3));
  EXPECT_FALSE(scene.task->success(scene.world));  // four, when three were asked
}

TEST(StackBlocks, ADistractorInTheStackOrBlocksSideBySideAreNotAStack) {
  Scene with_distractor(5, 0);  // stack 2
  with_distractor.place("target1", with_distractor.level(0));
  with_distractor.place("distractor1", with_distractor.level(1));
  EXPECT_FALSE(with_distractor.task->success(with_distractor.world));

  Scene side_by_side(5, 0);
  side_by_side.place("target1", side_by_side.level(0) + Eigen::Vector3d(0.027, 0, 0));
  side_by_side.place("target2", side_by_side.level(0) - Eigen::Vector3d(0.027, 0, 0));
  EXPECT_FALSE(side_by_side.task->success(side_by_side.world));
  side_by_side.place("target3", side_by_side.level(1) + Eigen::Vector3d(0.027, 0, 0));  // now 2 high, 3 in all
  EXPECT_FALSE(side_by_side.task->success(side_by_side.world));
}

TEST(StackBlocks, ASeedDecidesTheScene) {
  Scene a(11, 4), b(11, 4), c(12, 4);
  for (const char* name : {"target1", "distractor3", "target_plane"}) {
    EXPECT_TRUE(a.pose(name).isApprox(b.pose(name), 0)) << name;
    EXPECT_FALSE(a.pose(name).isApprox(c.pose(name), 1e-6)) << name;
  }
}

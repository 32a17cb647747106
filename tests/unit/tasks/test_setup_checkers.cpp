// setup_checkers: the opening position with 1-3 checkers stacked beside the board; success
// only with every checker resting on its own square and nothing held (one still off, one on
// a wrong square, one held: no); a seed decides the scene. Home squares are worked out here
// from the rules of the game (red on the dark squares of rows 0-2, black of rows 5-7).
#include <gtest/gtest.h>

#include "task_scene.hpp"

using namespace qte;

namespace {

constexpr double kSquare = 0.04, kCheckerHeight = 0.0072;

struct Scene : test_support::TaskScene {
  Scene(uint64_t seed, int variation) : TaskScene("setup_checkers", seed, variation) {}
  Eigen::Isometry3d board() const { return pose("board"); }

  // The k-th dark square (row + column even) of the side's home rows, as the checker rests on it.
  Eigen::Vector3d home(const std::string& name) const {
    const bool red = name.rfind("red", 0) == 0;
    int k = std::stoi(name.substr(red ? 3 : 5));
    for (int row : red ? std::vector<int>{0, 1, 2} : std::vector<int>{5, 6, 7})
      for (int column = 0; column < 8; ++column)
        if ((row + column) % 2 == 0 && k-- == 0)
          return board() * Eigen::Vector3d((column - 3.5) * kSquare, (row - 3.5) * kSquare,
                                           0.005 + world::kHullMargin + kCheckerHeight / 2);
    ADD_FAILURE() << name;
    return {};
  }
  std::vector<std::string> checkers() const {
    std::vector<std::string> names;
    for (int i = 0; i < 12; ++i) names.insert(names.end(), {"red" + std::to_string(i), "black" + std::to_string(i)});
    return names;
  }
  std::vector<std::string> off_board() const {
    std::vector<std::string> off;
    for (const auto& name : checkers())
      if ((pose(name).translation() - home(name)).head<2>().norm() > 0.001) off.push_back(name);
    std::sort(off.begin(), off.end(), [&](const std::string& a, const std::string& b) {
      return pose(a).translation().z() > pose(b).translation().z();  // the top of the stack first
    });
    return off;
  }
  // Grasped and placed square to the board (as the expert does).
  void place(const std::string& name, const Eigen::Vector3d& to, bool release = true) {
    const double yaw = std::atan2(board().linear()(1, 0), board().linear()(0, 0));
    TaskScene::place(name, yaw, to, yaw, release);
  }
};

}  // namespace

TEST(SetupCheckers, TheOpeningPositionWithTheVariationsCheckersStackedBeside) {
  for (uint64_t seed = 0; seed < 12; ++seed) {
    const int variation = static_cast<int>(seed % 3);
    Scene scene(seed, variation);
    const auto off = scene.off_board();
    ASSERT_EQ(off.size(), static_cast<std::size_t>(variation + 1));
    // On the table beside the board (5 cm past its edge), one on another.
    const Eigen::Vector3d spot = scene.board().inverse() * scene.pose(off.back()).translation();
    EXPECT_NEAR(spot.x(), 0.0, 1e-6);
    EXPECT_NEAR(spot.y(), 0.21, 1e-6);
    for (std::size_t i = 0; i < off.size(); ++i) {
      const Eigen::Vector3d p = scene.pose(off[i]).translation();
      EXPECT_NEAR((p - scene.pose(off.back()).translation()).head<2>().norm(), 0.0, 1e-6);
      // Stacked hulls rest a margin above what is under them.
      const double level = static_cast<double>(off.size() - i - 1);
      EXPECT_NEAR(p.z(), scene.world.layout().table_height_m + level * (kCheckerHeight + 2 * world::kHullMargin) +
                             world::kHullMargin + kCheckerHeight / 2, 1e-6);
    }
    for (const auto& name : scene.checkers())
      if (std::find(off.begin(), off.end(), name) == off.end())
        EXPECT_NEAR((scene.pose(name).translation() - scene.home(name)).norm(), 0.0, 1e-6) << name;
    EXPECT_FALSE(scene.task->success(scene.world));
  }
}

TEST(SetupCheckers, SuccessIsEveryCheckerOnItsSquareWithNothingHeld) {
  Scene scene(4, 1);  // two off the board
  const auto off = scene.off_board();
  ASSERT_EQ(off.size(), 2u);
  scene.place(off[0], scene.home(off[0]));
  EXPECT_FALSE(scene.task->success(scene.world));  // one still off
  scene.place(off[1], scene.home(off[1]), /*release=*/false);
  EXPECT_FALSE(scene.task->success(scene.world));  // held over its square
  scene.world.open_gripper();
  scene.world.settle(0.5);
  EXPECT_TRUE(scene.task->success(scene.world));
}

TEST(SetupCheckers, ACheckerOnAWrongSquareIsNotSetUp) {
  Scene scene(4, 0);
  const auto off = scene.off_board();
  ASSERT_EQ(off.size(), 1u);
  // The light square next to its home (empty in the opening position): one square along x.
  const Eigen::Vector3d next = scene.home(off[0]) + scene.board().linear() * Eigen::Vector3d(kSquare, 0, 0);
  scene.place(off[0], next);
  EXPECT_FALSE(scene.task->success(scene.world));
  scene.place(off[0], scene.home(off[0]));
  EXPECT_TRUE(scene.task->success(scene.world));
}

// The published grid puts the place pose up to 0.95 cm from the expert's in height: a checker
// carried below the board's top stops on the board (it slips in the grip) and is set up when
// let go, as it would be in a real hand.
TEST(SetupCheckers, ACheckerCarriedBelowTheBoardsTopStopsOnItAndIsSetUp) {
  for (uint64_t seed : {3, 5}) {
    Scene scene(seed, 0);
    const auto off = scene.off_board();
    ASSERT_EQ(off.size(), 1u);
    const Eigen::Vector3d low = scene.home(off[0]) - Eigen::Vector3d(0, 0, 0.0095 + 0.005);  // 0.95 cm below the place pose
    scene.place(off[0], low, /*release=*/false);
    ASSERT_EQ(scene.world.held_object(), scene.world.object_id(off[0]));
    EXPECT_NEAR(scene.pose(off[0]).translation().z(), scene.home(off[0]).z(), 0.0015) << "seed " << seed;
    scene.world.open_gripper();
    scene.world.settle(0.5);
    EXPECT_NEAR((scene.pose(off[0]).translation() - scene.home(off[0])).norm(), 0.0, 0.003) << "seed " << seed;
    EXPECT_TRUE(scene.task->success(scene.world)) << "seed " << seed;
  }
}

TEST(SetupCheckers, ASeedDecidesTheScene) {
  Scene a(11, 2), b(11, 2), c(12, 2);
  EXPECT_TRUE(a.board().isApprox(b.board(), 0));
  EXPECT_FALSE(a.board().isApprox(c.board(), 1e-6));
  EXPECT_EQ(a.off_board(), b.off_board());
  EXPECT_EQ(a.task->episode_length(), 25);
  EXPECT_EQ(a.task->variation_count(), 3);
}

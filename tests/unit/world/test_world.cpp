// The world's objects: every shape kind is a rigid body that falls and rests on the table.
#include <gtest/gtest.h>

#include "common/error.hpp"
#include "world/world.hpp"
#include "test_support.hpp"

using namespace qte;

TEST(World, EveryShapeFallsAndRestsOnTheTable) {
  world::World world(test_support::xarm());
  const double table = world.layout().table_height_m;
  // A triangular prism as a convex hull (pick_and_lift_small's shapes are hulls like it).
  world::ObjectSpec prism;
  prism.name = "prism";
  prism.shape = world::ObjectSpec::Shape::convex_hull;
  for (double z : {-0.02, 0.02})
    for (const auto& xy : {Eigen::Vector2d(0.03, 0), Eigen::Vector2d(-0.015, 0.026), Eigen::Vector2d(-0.015, -0.026)})
      prism.hull_points.emplace_back(xy.x(), xy.y(), z);
  prism.pose.translation() << 0.1, 0.1, table + 0.10;
  world::ObjectSpec box, cylinder, sphere;
  box.name = "box";
  box.size = Eigen::Vector3d(0.04, 0.04, 0.04);
  box.pose.translation() << 0.1, -0.1, table + 0.10;
  cylinder.name = "cylinder";
  cylinder.shape = world::ObjectSpec::Shape::cylinder;
  cylinder.size = Eigen::Vector3d(0.02, 0.06, 0);
  cylinder.pose.translation() << 0.2, 0.0, table + 0.10;
  sphere.name = "sphere";
  sphere.shape = world::ObjectSpec::Shape::sphere;
  sphere.size = Eigen::Vector3d(0.02, 0, 0);
  sphere.pose.translation() << 0.25, 0.2, table + 0.10;
  for (const auto* spec : {&prism, &box, &cylinder, &sphere}) world.add_object(*spec);
  world.settle(2.0);
  EXPECT_NEAR(world.object_pose(world.object_id("prism")).translation().z(), table + 0.02, 0.004);
  EXPECT_NEAR(world.object_pose(world.object_id("box")).translation().z(), table + 0.02, 0.004);
  EXPECT_NEAR(world.object_pose(world.object_id("cylinder")).translation().z(), table + 0.03, 0.004);
  EXPECT_NEAR(world.object_pose(world.object_id("sphere")).translation().z(), table + 0.02, 0.004);
  EXPECT_THROW(world.object_id("nothing"), Error);
  EXPECT_THROW(world.add_object(box), Error);  // names are unique
}

TEST(World, ObjectBoxesAreTheShapesOwnBoundsInTheObjectFrame) {
  world::World world(test_support::xarm());
  world::ObjectSpec box, cylinder, sphere, hull, compound;
  box.name = "box";
  box.size = Eigen::Vector3d(0.04, 0.06, 0.02);
  cylinder.name = "cylinder";
  cylinder.shape = world::ObjectSpec::Shape::cylinder;
  cylinder.size = Eigen::Vector3d(0.02, 0.06, 0);  // radius, height
  sphere.name = "sphere";
  sphere.shape = world::ObjectSpec::Shape::sphere;
  sphere.size = Eigen::Vector3d(0.03, 0, 0);
  hull.name = "hull";
  hull.shape = world::ObjectSpec::Shape::convex_hull;
  hull.hull_points = {{0, 0, 0}, {0.05, 0, 0}, {0, 0.02, 0}, {0, 0, 0.07}};
  compound.name = "compound";  // off-centre pieces: a cup's origin is its bottom
  compound.shape = world::ObjectSpec::Shape::compound;
  compound.pieces = {{{-0.01, -0.01, 0}, {0.01, 0.01, 0}, {0, 0, 0.02}}, {{0.1, 0, 0.05}, {0.11, 0.01, 0.06}, {0.1, 0.01, 0.05}}};
  double x = 0;
  for (auto* spec : {&box, &cylinder, &sphere, &hull, &compound}) {
    spec->mass_kg = 0;
    x += 0.2;
    spec->pose.translation() << x, 0, 1.5;  // apart, in the air: nothing touches
    world.add_object(*spec);
  }
  auto expect_box = [&](const std::string& name, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
    const Eigen::AlignedBox3d b = world.object_box(world.object_id(name));
    EXPECT_TRUE(b.min().isApprox(lo, 1e-12)) << name << ": " << b.min().transpose();
    EXPECT_TRUE(b.max().isApprox(hi, 1e-12)) << name << ": " << b.max().transpose();
  };
  expect_box("box", {-0.02, -0.03, -0.01}, {0.02, 0.03, 0.01});
  expect_box("cylinder", {-0.02, -0.02, -0.03}, {0.02, 0.02, 0.03});
  expect_box("sphere", {-0.03, -0.03, -0.03}, {0.03, 0.03, 0.03});
  expect_box("hull", {0, 0, 0}, {0.05, 0.02, 0.07});
  expect_box("compound", {-0.01, -0.01, 0}, {0.11, 0.01, 0.06});
}

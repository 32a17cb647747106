// The world's objects: every shape kind is a rigid body that falls and rests on the table.
#include <gtest/gtest.h>

#include "common/error.hpp"
#include "sim_step/trajectory_helpers.hpp"
#include "tasks/task.hpp"
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

// The fingers close on what lies between their 2 cm pads: a 7 x 14 cm phone turned 20 degrees
// to the jaws is 8.2 cm across the pads (its whole length would span 11.4 cm of the closing
// axis) and fits the 85 mm stroke; turned 35 degrees it is 9.9 cm across and does not. An
// object that fits is held with the fingers at its width across the pads.
TEST(World, TheFingersCloseOnWhatLiesBetweenTheirPads) {
  const auto width_across_pads = [](double yaw) {  // the phone's 3.5 cm half width, the pads' 1 cm half width
    return 2 * (0.035 / std::cos(yaw) + 0.01 * std::tan(yaw));
  };
  for (double degrees : {0.0, 10.0, 20.0, 35.0}) {
    SCOPED_TRACE(std::to_string(degrees) + " degrees");
    world::World world(test_support::xarm());
    const double table = world.layout().table_height_m, yaw = degrees * M_PI / 180;
    world::ObjectSpec phone;
    phone.name = "phone";
    phone.size = Eigen::Vector3d(0.07, 0.14, 0.01);  // grasped across its width, x
    phone.pose.linear() = Eigen::AngleAxisd(M_PI / 2 + yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    phone.pose.translation() << 0.15, 0.0, table + 0.005;
    phone.mass_kg = 0.15;
    const int id = world.add_object(phone);
    Eigen::Isometry3d tcp = Eigen::Isometry3d::Identity();
    tcp.linear() = tasks::top_down(0);  // closing along world y, the phone's width turned from it by yaw
    tcp.translation() << 0.15, 0.0, table + 0.005;
    world.set_robot_state(test_support::ik_world(world, tcp), 0.085);
    const bool fits = width_across_pads(yaw) <= 0.085 + 0.004;
    EXPECT_EQ(world.close_gripper(), fits ? id : -1);
    if (fits) {
      EXPECT_NEAR(world.finger_opening_m(), width_across_pads(yaw), 0.002);
    }
  }
}

// Beside the pads' band, or with only a corner of it in the band (no more than 2 mm across),
// nothing is held; an object off the jaws' centre is held while all of it lies within the stroke.
TEST(World, NothingIsHeldThatThePadsDoNotMeet) {
  struct Case {
    const char* what;
    double yaw_deg, x, y;  // the 4 cm cube's yaw and offset from the TCP, along and across the pads
    bool held;
  };
  const Case cases[] = {
      {"beside the band", 0, 0.032, 0, false},  // 1.2 cm past the pads' edge
      {"a corner's tip in the band", 45, 0.0375, 0, false},  // 0.8 mm of its corner: 1.6 mm across
      {"well in the band at 45 degrees", 45, 0.015, 0, true},
      {"off centre, within the stroke", 0, 0, 0.02, true},   // 4.0 to 0 cm from the centre line
      {"off centre, past the stroke", 0, 0, 0.03, false},    // its far side 5 cm out: past 4.45
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.what);
    world::World world(test_support::xarm());
    const double table = world.layout().table_height_m;
    world::ObjectSpec cube;
    cube.name = "cube";
    cube.size = Eigen::Vector3d(0.04, 0.04, 0.04);
    cube.pose.linear() = Eigen::AngleAxisd(c.yaw_deg * M_PI / 180, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    cube.pose.translation() << 0.15, 0.0, table + 0.02;
    cube.mass_kg = 0.1;
    const int id = world.add_object(cube);
    Eigen::Isometry3d tcp = Eigen::Isometry3d::Identity();
    tcp.linear() = tasks::top_down(0);  // TCP x along world x, TCP y along world -y
    tcp.translation() << 0.15 - c.x, c.y, table + 0.02;
    world.set_robot_state(test_support::ik_world(world, tcp), 0.085);
    EXPECT_EQ(world.close_gripper(), c.held ? id : -1);
  }
}

namespace {

// A 4 cm box held from above at its centre, 10 cm over a static slab whose top is at `slab_top`.
struct HeldOverSlab {
  world::World world{test_support::xarm()};
  int box = -1;
  double slab_top = 0;
  HeldOverSlab() {
    const double table = world.layout().table_height_m;
    world::ObjectSpec slab, held;
    slab.name = "slab";
    slab.size = Eigen::Vector3d(0.2, 0.2, 0.02);
    slab.pose.translation() << 0.15, 0.0, table + 0.01;
    slab.mass_kg = 0;
    slab_top = table + 0.02;
    held.name = "box";
    held.size = Eigen::Vector3d(0.04, 0.04, 0.04);
    held.pose.translation() << 0.15, 0.0, slab_top + 0.12;
    world.add_object(slab);
    box = world.add_object(held);
    world.set_robot_state(test_support::ik_world(world, tcp_at(slab_top + 0.12)), 0.085);
    EXPECT_EQ(world.close_gripper(), box);
  }
  static Eigen::Isometry3d tcp_at(double z) {
    Eigen::Isometry3d tcp = Eigen::Isometry3d::Identity();
    tcp.linear() = tasks::top_down(0);
    tcp.translation() << 0.15, 0.0, z;
    return tcp;
  }
  double box_bottom() const { return world.object_pose(box).translation().z() - 0.02; }
};

}  // namespace

// What a held object is pressed onto stops it: it slips up in the grip rather than go into the
// slab, stays held, and rests on the slab when let go.
TEST(World, AHeldObjectPressedOntoSomethingSlipsInTheGripInsteadOfEnteringIt) {
  HeldOverSlab scene;
  // Down until the box's centre would be 1.5 cm below the slab's top + 2 cm: 1.5 cm into it.
  scene.world.step_towards(test_support::ik_world(scene.world, HeldOverSlab::tcp_at(scene.slab_top + 0.005)),
                           scene.world.finger_opening_m(), 1.0);
  EXPECT_EQ(scene.world.held_object(), scene.box);
  EXPECT_NEAR(scene.box_bottom(), scene.slab_top, world::World::kSlipTolerance_m + 0.001);
  const double tcp_z = scene.world.tcp_pose().translation().z();
  EXPECT_NEAR(tcp_z, scene.slab_top + 0.005, 0.002);  // the gripper went on down
  scene.world.open_gripper();
  scene.world.settle(0.5);
  EXPECT_NEAR(scene.box_bottom(), scene.slab_top, 0.002);
}

// Pressing sideways is not a slip: a held object swept into a standing one pushes it and keeps
// its own place in the grip.
TEST(World, AHeldObjectSweptSidewaysPushesWhatItMeetsAndKeepsItsGrip) {
  HeldOverSlab scene;
  world::ObjectSpec standing;
  standing.name = "standing";
  standing.size = Eigen::Vector3d(0.03, 0.03, 0.06);
  standing.pose.translation() << 0.15, 0.06, scene.slab_top + 0.03 + world::kHullMargin;
  const int other = scene.world.add_object(standing);
  scene.world.step_towards(test_support::ik_world(scene.world, HeldOverSlab::tcp_at(scene.slab_top + 0.03)),
                           scene.world.finger_opening_m(), 0.5);
  const Eigen::Isometry3d in_grip = scene.world.tcp_pose().inverse() * scene.world.object_pose(scene.box);
  const Eigen::Vector3d start = scene.world.object_pose(other).translation();
  Eigen::Isometry3d tcp = HeldOverSlab::tcp_at(scene.slab_top + 0.03);
  tcp.translation().y() += 0.1;
  scene.world.step_towards(test_support::ik_world(scene.world, tcp), scene.world.finger_opening_m(), 1.0);
  EXPECT_GT((scene.world.object_pose(other).translation() - start).norm(), 0.02);
  const Eigen::Isometry3d after = scene.world.tcp_pose().inverse() * scene.world.object_pose(scene.box);
  EXPECT_NEAR((after.translation() - in_grip.translation()).norm(), 0.0, 1e-6);
}

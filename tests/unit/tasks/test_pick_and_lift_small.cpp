// pick_and_lift_small: five small look-alikes apart on the table with the zone clear of them,
// footprints that fit one depth-0 voxel; star and moon as compounds that the cameras see with
// their notches and that Bullet stands on the table; success only for the variation's shape,
// held and in the zone; a seed decides the scene.
#include <gtest/gtest.h>

#include <BulletCollision/CollisionDispatch/btCollisionWorld.h>
#include <cmath>

#include "render/ray_caster.hpp"
#include "tasks/shapes.hpp"
#include "task_scene.hpp"

using namespace qte;

namespace {

const char* const kShapes[] = {"cube", "cylinder", "triangular_prism", "star", "moon"};
constexpr double kSize = 0.0209;

struct Scene : test_support::TaskScene {
  Scene(uint64_t seed, int variation) : TaskScene("pick_and_lift_small", seed, variation) {}
};

double area(const tasks::Polygon& p) {  // shoelace
  double twice = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    const auto& a = p[i];
    const auto& b = p[(i + 1) % p.size()];
    twice += a.x() * b.y() - b.x() * a.y();
  }
  return std::abs(twice) / 2;
}

// Every turn of the outline the same way (or straight): convex.
bool convex(const tasks::Polygon& p) {
  int positive = 0, negative = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    const Eigen::Vector2d e1 = p[(i + 1) % p.size()] - p[i], e2 = p[(i + 2) % p.size()] - p[(i + 1) % p.size()];
    const double cross = e1.x() * e2.y() - e1.y() * e2.x();
    positive += cross > 1e-12;
    negative += cross < -1e-12;
  }
  return positive == 0 || negative == 0;
}

}  // namespace

TEST(PickAndLiftSmall, StarAndMoonPiecesAreConvexAndCoverTheOutline) {
  const auto star = tasks::star_pieces(5, 0.014, 0.0065);
  ASSERT_EQ(star.size(), 5u);
  double star_area = 0;
  for (const auto& piece : star) {
    EXPECT_TRUE(convex(piece));
    star_area += area(piece);
  }
  // Ten triangles centre-notch-tip, each r R sin(36 deg) / 2.
  EXPECT_NEAR(star_area, 10 * 0.014 * 0.0065 * std::sin(M_PI / 5) / 2, 1e-12);

  const double r = 0.013, d = 0.009;
  const auto moon = tasks::crescent_pieces(r, d, 10);
  double moon_area = 0;
  for (const auto& piece : moon) {
    EXPECT_TRUE(convex(piece));
    moon_area += area(piece);
  }
  // The disc less its overlap (a lens) with the shifted disc; the strips cut the curves as chords.
  const double lens = 2 * r * r * std::acos(d / (2 * r)) - d / 2 * std::sqrt(4 * r * r - d * d);
  EXPECT_NEAR(moon_area, M_PI * r * r - lens, 0.04 * (M_PI * r * r - lens));
}

namespace {

// The shapes on the table, 10 cm apart, the zone 30 cm up and 15 cm from each in plan view.
void expect_lookalikes_apart_and_the_zone_clear(uint64_t seed, int variation) {
  Scene scene(seed, variation);
  const double table = scene.world.layout().table_height_m;
  const Eigen::Vector3d zone = scene.pose("success_zone").translation();
  EXPECT_NEAR(zone.z(), table + 0.3, 1e-6);  // Bullet keeps floats
  for (const char* a : kShapes) {
    const Eigen::Vector3d p = scene.pose(a).translation();
    EXPECT_NEAR(p.z(), table + world::kHullMargin + kSize / 2, 1e-6) << a;  // resting on its margin
    EXPECT_GE(p.x(), 0.0);
    EXPECT_LE(p.x(), 0.3);
    EXPECT_LE(std::abs(p.y()), 0.25);
    EXPECT_GE((p - zone).head<2>().norm(), 0.15 - 1e-6) << a;
    for (const char* b : kShapes)
      if (a != b) EXPECT_GE((p - scene.pose(b).translation()).head<2>().norm(), 0.1) << a << " " << b;
    EXPECT_TRUE(scene.world.object_spec(scene.world.object_id(a)).graspable);
  }
}

}  // namespace

TEST(PickAndLiftSmall, FiveLookalikesApartOnTheTableAndTheZoneClearOfThem) {
  for (uint64_t seed = 0; seed < 30; ++seed) expect_lookalikes_apart_and_the_zone_clear(seed, seed % 5);
}

// An exploration scene (chunk 109 of a seed-0 run, its 7th episode) whose first layout of the
// shapes leaves no point 15 cm from all five: the layout is drawn again, and the scene builds.
TEST(PickAndLiftSmall, ALayoutWithNoRoomForTheZoneIsDrawnAgain) {
  expect_lookalikes_apart_and_the_zone_clear(2833259837691174098ull, 0);
}

TEST(PickAndLiftSmall, FootprintsFitOneCoarseVoxelAndAreCentredOnTheirBox) {
  Scene scene(0, 0);
  for (const char* name : kShapes) {
    const world::ObjectSpec& spec = scene.world.object_spec(scene.world.object_id(name));
    Eigen::AlignedBox3d box;
    for (const auto& p : spec.hull_points) box.extend(p);
    for (const auto& piece : spec.pieces)
      for (const auto& p : piece) box.extend(p);
    const Eigen::Vector3d extent = box.sizes();
    EXPECT_GE(extent.head<2>().minCoeff(), 0.019) << name;  // 1.9-2.8 cm: one 6.25 cm voxel each
    EXPECT_LE(extent.head<2>().maxCoeff(), 0.03) << name;
    EXPECT_NEAR(extent.z(), kSize, 1e-12) << name;
    EXPECT_LE(box.center().head<2>().norm(), 0.0036) << name;  // the triangle's centroid is 3.5 mm off its box's
    EXPECT_EQ(spec.shape == world::ObjectSpec::Shape::compound, std::string(name) == "star" || std::string(name) == "moon")
        << name;
  }
}

// Rays straight down: onto a star's tip they meet its top face; into the notch between two tips
// (inside the star's outer circle) they pass to the table. Likewise the moon's bite.
TEST(PickAndLiftSmall, CamerasSeeTheNotchesOfTheCompounds) {
  world::World world(test_support::xarm());
  const double table = world.layout().table_height_m;
  const Eigen::Vector3d star_at(0.1, 0.1, 0), moon_at(0.1, -0.1, 0);
  world.add_object(tasks::standing_prism(world, "star", tasks::star_pieces(5, 0.014, 0.0065), kSize, star_at, 0, {1, 1, 1}));
  world.add_object(tasks::standing_prism(world, "moon", tasks::crescent_pieces(0.013, 0.009, 10), kSize, moon_at, 0, {1, 1, 1}));
  const render::RayCaster caster(world.collision_world());
  auto height_below = [&](double x, double y) {
    render::RayHit hit;
    EXPECT_TRUE(caster.cast({x, y, table + 0.5}, {0, 0, -1}, 1.0, hit));
    return table + 0.5 - hit.distance;
  };
  const double tip = M_PI / 2, notch = M_PI / 2 + M_PI / 5;
  EXPECT_NEAR(height_below(star_at.x() + 0.012 * std::cos(tip), star_at.y() + 0.012 * std::sin(tip)), table + kSize, 1e-6);
  EXPECT_NEAR(height_below(star_at.x() + 0.011 * std::cos(notch), star_at.y() + 0.011 * std::sin(notch)), table, 1e-6);
  EXPECT_NEAR(height_below(star_at.x(), star_at.y()), table + kSize, 1e-6);
  // Through the moon's middle (y = 0) the crescent spans x in about [-8.7, 0.3] mm about its
  // box centre (the disc's centre about +4.3 mm: half of r - d/2 less what the strips cut off
  // the tips): 1 mm right of the centre is the bite, 5 mm left the crescent.
  EXPECT_NEAR(height_below(moon_at.x() + 0.001, moon_at.y()), table, 1e-6);
  EXPECT_NEAR(height_below(moon_at.x() - 0.005, moon_at.y()), table + kSize, 1e-6);
}

TEST(PickAndLiftSmall, CompoundsRestOnTheTableAsBulletCollidesThem) {
  world::World world(test_support::xarm());
  const double table = world.layout().table_height_m;
  world::ObjectSpec star = tasks::standing_prism(world, "star", tasks::star_pieces(5, 0.014, 0.0065), kSize, {0.1, 0.1, 0}, 0.3, {1, 1, 1});
  star.mass_kg = 0.03;
  star.pose.translation().z() += 0.05;  // dropped from 5 cm
  world.add_object(star);
  world.settle(1.5);
  const Eigen::Isometry3d rest = world.object_pose(0);
  EXPECT_NEAR(rest.translation().z(), table + kSize / 2, 0.003);
  EXPECT_GT(rest.linear()(2, 2), 0.99);  // still upright
}

TEST(PickAndLiftSmall, SuccessIsTheVariationsShapeHeldInTheZone) {
  for (int variation = 0; variation < 5; ++variation) {
    Scene scene(7, variation);
    const auto expert = scene.task->expert_waypoints(scene.world);
    ASSERT_EQ(expert.size(), 4u);
    const int target = scene.world.object_id(kShapes[variation]);
    EXPECT_TRUE(expert[1].tcp_pose.translation().isApprox(scene.pose(kShapes[variation]).translation(), 1e-12));
    EXPECT_FALSE(scene.task->success(scene.world));
    // Grasp the target, then carry it into the zone.
    scene.world.set_robot_state(test_support::ik_world(scene.world, expert[1].tcp_pose), 0.085);
    ASSERT_EQ(scene.world.close_gripper(), target) << kShapes[variation];
    EXPECT_FALSE(scene.task->success(scene.world));  // held, on the table
    scene.world.set_robot_state(test_support::ik_world(scene.world, expert[3].tcp_pose), scene.world.finger_opening_m());
    EXPECT_TRUE(scene.task->success(scene.world)) << kShapes[variation];
  }
  // The wrong shape held in the zone: no.
  Scene scene(7, 3);  // the star
  const auto expert = scene.task->expert_waypoints(scene.world);
  auto moved = [&](Eigen::Isometry3d pose, const Eigen::Vector3d& to) { pose.translation() = to; return pose; };
  scene.world.set_robot_state(test_support::ik_world(scene.world, moved(expert[1].tcp_pose, scene.pose("moon").translation())), 0.085);
  ASSERT_EQ(scene.world.close_gripper(), scene.world.object_id("moon"));
  scene.world.set_robot_state(test_support::ik_world(scene.world, expert[3].tcp_pose), scene.world.finger_opening_m());
  EXPECT_FALSE(scene.task->success(scene.world));
}

TEST(PickAndLiftSmall, ASeedDecidesTheScene) {
  Scene a(11, 2), b(11, 2), c(12, 2);
  for (const char* name : kShapes) {
    EXPECT_TRUE(a.pose(name).isApprox(b.pose(name), 0)) << name;
    EXPECT_FALSE(a.pose(name).isApprox(c.pose(name), 1e-6)) << name;
  }
}

// pick_and_lift: grasp the block of the variation's colour and lift it into the green
// success sphere; two distractor blocks of other colours (RLBench's pick_and_lift).
#include "tasks/blocks.hpp"

namespace qte::tasks {
namespace {

constexpr double kZoneRadius = 0.04;

class PickAndLift : public Task {
 public:
  std::string name() const override { return "pick_and_lift"; }
  int variation_count() const override { return static_cast<int>(colours().size()); }
  std::string description(int variation) const override {
    return "pick up the " + colours()[variation].name + " block and lift it up to the target";
  }

  void build(sim::World& world, int variation, std::mt19937_64& rng) override {
    // Three blocks and, above the table, the zone: apart in plan view, so the arm over a
    // block never reaches into the zone (which a camera-based planner sees as an obstacle).
    const auto positions = sample_separated(rng, 4, {kRegionMinX, kRegionMinY, 0},
                                            {kRegionMaxX, kRegionMaxY, 0}, 0.15);
    const auto distractors = pick_distinct(rng, 2, variation_count(), variation);
    std::uniform_real_distribution<double> yaw(-M_PI / 4, M_PI / 4);
    world.add_object(block(world, "target", positions[0], yaw(rng), colours()[variation].rgb));
    for (int i = 0; i < 2; ++i)
      world.add_object(block(world, "distractor" + std::to_string(i + 1), positions[i + 1], yaw(rng),
                             colours()[distractors[i]].rgb));
    sim::ObjectSpec zone;
    zone.name = "success_zone";
    zone.shape = sim::ObjectSpec::Shape::sphere;
    zone.size = Eigen::Vector3d(kZoneRadius, 0, 0);
    zone.pose.translation() << positions[3].x(), positions[3].y(), world.layout().table_height_m + 0.3;
    zone.mass_kg = 0;
    zone.collides = false;
    zone.graspable = false;
    zone.appearance.colour = Eigen::Vector3f(0.55f, 0.95f, 0.55f);
    world.add_object(zone);
  }

  bool success(const sim::World& world) const override {
    const int target = world.object_id("target");
    const Eigen::Vector3d zone = world.object_pose(world.object_id("success_zone")).translation();
    return world.held_object() == target &&
           (world.object_pose(target).translation() - zone).norm() <= kZoneRadius;
  }

  std::vector<Waypoint> expert_waypoints(const sim::World& world) const override {
    auto waypoints = grasp_and_lift(world, world.object_id("target"), 0.15);
    Waypoint into_zone = waypoints.back();
    into_zone.tcp_pose.translation() = world.object_pose(world.object_id("success_zone")).translation();
    into_zone.ignore_collisions = false;
    waypoints.push_back(into_zone);
    return waypoints;
  }
};

}  // namespace

std::unique_ptr<Task> make_pick_and_lift() { return std::make_unique<PickAndLift>(); }

}  // namespace qte::tasks

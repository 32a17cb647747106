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

  void build(world::World& world, int variation, std::mt19937_64& rng) override {
    // Three blocks and, above the table, the zone: apart in plan view, so the arm over a
    // block never reaches into the zone (which a camera-based planner sees as an obstacle).
    const auto positions = sample_separated(rng, 4, {kRegionMinX, kRegionMinY, 0},
                                            {kRegionMaxX, kRegionMaxY, 0}, 0.15);
    const auto distractors = pick_distinct(rng, 2, variation_count(), variation);
    std::uniform_real_distribution<double> yaw(-M_PI / 4, M_PI / 4);
    world::ObjectSpec target = block(world, "target", positions[0], yaw(rng), colours()[variation].rgb);
    target.role = world::ObjectSpec::Role::target;
    world.add_object(target);
    for (int i = 0; i < 2; ++i) {
      world::ObjectSpec distractor = block(world, "distractor" + std::to_string(i + 1), positions[i + 1], yaw(rng),
                                           colours()[distractors[i]].rgb);
      distractor.role = world::ObjectSpec::Role::distractor;
      world.add_object(distractor);
    }
    world.add_object(success_zone(world, positions[3], kZoneRadius));
  }

  bool success(const world::World& world) const override {
    return held_in_zone(world, world.object_id("target"), kZoneRadius);
  }

  std::vector<Waypoint> expert_waypoints(const world::World& world) const override {
    return lift_into_zone(world, world.object_id("target"));
  }
};

}  // namespace

std::unique_ptr<Task> make_pick_and_lift() { return std::make_unique<PickAndLift>(); }

}  // namespace qte::tasks

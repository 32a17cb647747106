// reach_target: touch the sphere of the variation's colour; two distractor spheres of other
// colours float nearby (RLBench's reach_target).
#include "tasks/catalogue.hpp"

namespace qte::tasks {
namespace {

constexpr double kRadius = 0.025;

class ReachTarget : public Task {
 public:
  std::string name() const override { return "reach_target"; }
  int variation_count() const override { return static_cast<int>(colours().size()); }
  std::string description(int variation) const override {
    return "reach the " + colours()[variation].name + " target";
  }

  void build(world::World& world, int variation, std::mt19937_64& rng) override {
    const double table = world.layout().table_height_m;
    // Distractors never hover right above the target: the expert reaches it from above.
    std::vector<Eigen::Vector3d> positions;
    auto above_target = [&](const Eigen::Vector3d& p) {
      return p.z() > positions[0].z() && (p - positions[0]).head<2>().norm() < 0.12;
    };
    do {
      positions = sample_separated(rng, 3, {kRegionMinX, kRegionMinY, table + 0.1},
                                   {kRegionMaxX, kRegionMaxY, table + 0.35}, 0.2);
    } while (above_target(positions[1]) || above_target(positions[2]));
    const auto distractor_colours = pick_distinct(rng, 2, variation_count(), variation);
    for (int i = 0; i < 3; ++i) {
      world::ObjectSpec sphere;
      sphere.name = i == 0 ? "target" : "distractor" + std::to_string(i);
      sphere.role = i == 0 ? world::ObjectSpec::Role::target : world::ObjectSpec::Role::distractor;
      sphere.shape = world::ObjectSpec::Shape::sphere;
      sphere.size = Eigen::Vector3d(kRadius, 0, 0);
      sphere.pose.translation() = positions[i];
      sphere.mass_kg = 0;  // floats where it was placed
      sphere.collides = false;
      sphere.graspable = false;
      sphere.appearance.colour = colours()[i == 0 ? variation : distractor_colours[i - 1]].rgb;
      world.add_object(sphere);
    }
  }

  bool success(const world::World& world) const override {
    const Eigen::Vector3d target = world.object_pose(world.object_id("target")).translation();
    return (world.tcp_pose().translation() - target).norm() <= kRadius;
  }

  std::vector<Waypoint> expert_waypoints(const world::World& world) const override {
    Waypoint reach;
    reach.tcp_pose.linear() = top_down(0);
    reach.tcp_pose.translation() = world.object_pose(world.object_id("target")).translation();
    return {reach};
  }
};

}  // namespace

std::unique_ptr<Task> make_reach_target() { return std::make_unique<ReachTarget>(); }

}  // namespace qte::tasks

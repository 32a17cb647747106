// pick_and_lift_small: five small shapes of one colour and height on the table — a cube
// (2.09 cm, RLBench's), a cylinder, a triangular prism, a star and a crescent moon — and a
// success sphere above the table; grasp the variation's shape and lift it into the sphere
// (RLBench's pick_and_lift_small). Footprints are 2.0-2.8 cm across: at 6.25 cm the shapes
// are one voxel each and alike; only the finer depths tell them apart. The other sizes are
// ours (RLBench's meshes are not public here): each shape fits the cube's bounding square
// or a little more, so none is told apart by size at depth 0.
#include "common/error.hpp"
#include "tasks/blocks.hpp"
#include "tasks/shapes.hpp"

namespace qte::tasks {
namespace {

constexpr double kSize = 0.0209;  // the cube's side and every shape's height
constexpr double kZoneRadius = 0.04;
const char* const kShapes[] = {"cube", "cylinder", "triangular_prism", "star", "moon"};

std::vector<Polygon> footprint(const std::string& shape) {
  if (shape == "cube") return {regular_polygon(4, kSize / std::sqrt(2.0))};
  if (shape == "cylinder") return {regular_polygon(24, kSize / 2)};  // a 24-gon: the look of a cylinder
  if (shape == "triangular_prism") return {regular_polygon(3, 0.014)};
  if (shape == "star") return star_pieces(5, 0.014, 0.0065);
  return crescent_pieces(0.014, 0.013, 16);
}

class PickAndLiftSmall : public Task {
 public:
  std::string name() const override { return "pick_and_lift_small"; }
  int variation_count() const override { return 5; }
  std::string description(int variation) const override {
    const std::string shape = kShapes[variation];
    return "pick up the " + (shape == "triangular_prism" ? std::string("triangular prism") : shape) +
           " and lift it up to the target";
  }

  void build(world::World& world, int variation, std::mt19937_64& rng) override {
    target_ = kShapes[variation];
    // The shapes 10 cm apart; the zone (above the table) 15 cm from each in plan view, so the
    // arm over a shape never reaches into it (the planner sees it as an obstacle). About one
    // layout in 800 leaves no room for the zone: it is drawn again from the same stream, so
    // every scene that had room is the scene it always was.
    std::vector<Eigen::Vector3d> positions;
    Eigen::Vector3d zone_xy;
    for (int layout = 0;; ++layout) {
      positions = sample_separated(rng, 5, {kRegionMinX, kRegionMinY, 0}, {kRegionMaxX, kRegionMaxY, 0}, 0.1);
      try {
        zone_xy = sample_away_from(rng, positions, {kRegionMinX, kRegionMinY, 0}, {kRegionMaxX, kRegionMaxY, 0}, 0.15);
        break;
      } catch (const Error&) {
        if (layout == 99) throw;
      }
    }
    std::uniform_real_distribution<double> yaw(-M_PI, M_PI);
    const Eigen::Vector3f colour(0.2f, 0.45f, 0.95f);
    for (int i = 0; i < 5; ++i) {
      world::ObjectSpec spec = standing_prism(world, kShapes[i], footprint(kShapes[i]), kSize, positions[i], yaw(rng), colour);
      spec.pose.translation().z() += world::kHullMargin;  // resting on its margin
      spec.mass_kg = 0.03;
      spec.graspable = true;
      spec.role = i == variation ? world::ObjectSpec::Role::target : world::ObjectSpec::Role::distractor;
      world.add_object(spec);
    }
    world.add_object(success_zone(world, zone_xy, kZoneRadius));
  }

  bool success(const world::World& world) const override {
    return held_in_zone(world, world.object_id(target_), kZoneRadius);
  }

  std::vector<Waypoint> expert_waypoints(const world::World& world) const override {
    return lift_into_zone(world, world.object_id(target_));
  }

 private:
  std::string target_;  // the shape of the variation the scene was built for
};

}  // namespace

std::unique_ptr<Task> make_pick_and_lift_small() { return std::make_unique<PickAndLiftSmall>(); }

}  // namespace qte::tasks

// stack_wine: a wine bottle and a rack (RLBench's stack_wine, one variation); put the bottle
// in the rack's slot. Success: the bottle's centre in the slot, resting there, not held
// (RLBench: inside a sensor in the rack). Ours lies on its side on the table (the issue lets
// it lie or stand; lying keeps every grasp top-down) and goes into a cradle: a base plate
// with two rails, yaw within +-45 degrees. Sizes are ours: a 29 cm bottle, 7.2 cm across
// (a 16-sided body, shoulder and neck), within the 85 mm stroke; a 26 x 16 cm rack whose slot
// is 10 cm wide between 3.5 cm rails, so the closed fingers clear them. The expert: above the
// bottle's middle, grasp, lift, over the slot square to it, down to 5 mm above resting, let go.
#include "tasks/blocks.hpp"
#include "tasks/shapes.hpp"

namespace qte::tasks {
namespace {

constexpr double kBodyRadius = 0.036, kBodyHalfLength = 0.09;
constexpr double kPlate = 0.01, kRailHeight = 0.035, kRailWidth = 0.015, kSlotHalfWidth = 0.05;
const Eigen::Vector2d kRackHalfSize(0.13, kSlotHalfWidth + kRailWidth + 0.015);

// The bottle along its x axis, its origin the body's centre (where it is grasped).
std::vector<Piece> bottle() {
  const double b = kBodyHalfLength;
  return rotated({frustum(16, kBodyRadius, kBodyRadius, -b, b), frustum(16, kBodyRadius, 0.014, b, b + 0.04),
                  frustum(12, 0.014, 0.014, b + 0.04, b + 0.11)},
                 Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitY()).toRotationMatrix());
}

// Height of the bottle's centre over what it lies on: the 16-gon's apothem, on a flat side.
double lying_height() { return kBodyRadius * std::cos(M_PI / 16) + world::kHullMargin; }

class StackWine : public Task {
 public:
  std::string name() const override { return "stack_wine"; }
  int variation_count() const override { return 1; }
  std::string description(int) const override { return "stack wine bottle"; }

  void build(world::World& world, int, std::mt19937_64& rng) override {
    const double table = world.layout().table_height_m;
    const double side = uniform(rng, 0, 1) < 0.5 ? -1 : 1;
    // The rack (origin: the centre of its plate's underside), the slot along its x axis.
    Eigen::Isometry3d rack = Eigen::Isometry3d::Identity();
    rack.linear() = Eigen::AngleAxisd(uniform(rng, -M_PI / 4, M_PI / 4), Eigen::Vector3d::UnitZ()).toRotationMatrix();
    rack.translation() << uniform(rng, 0.1, 0.2), side * uniform(rng, 0.13, 0.18), table;
    const double rx = kRackHalfSize.x(), rail = kSlotHalfWidth + kRailWidth;
    world.add_object(solid("rack", {box_piece({-rx, -kRackHalfSize.y(), 0}, {rx, kRackHalfSize.y(), kPlate}),
                                    box_piece({-rx, kSlotHalfWidth, kPlate}, {rx, rail, kPlate + kRailHeight}),
                                    box_piece({-rx, -rail, kPlate}, {rx, -kSlotHalfWidth, kPlate + kRailHeight})},
                           rack, {0.55f, 0.35f, 0.2f}));

    // The bottle on the other side, lying along a yaw within +-45 degrees.
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.linear() = Eigen::AngleAxisd(uniform(rng, -M_PI / 4, M_PI / 4), Eigen::Vector3d::UnitZ()).toRotationMatrix();
    pose.translation() << uniform(rng, 0.05, 0.2), -side * uniform(rng, 0.1, 0.16), table + lying_height();
    world::ObjectSpec spec = solid("wine_bottle", bottle(), pose, {0.1f, 0.35f, 0.15f});
    spec.mass_kg = 0.3;
    spec.graspable = true;
    spec.role = world::ObjectSpec::Role::target;
    spec.grasp_region = Eigen::AlignedBox3d(Eigen::Vector3d(-kBodyHalfLength, -kBodyRadius, -kBodyRadius),
                                            Eigen::Vector3d(kBodyHalfLength, kBodyRadius, kBodyRadius));
    world.add_object(spec);
  }

  bool success(const world::World& world) const override {
    const int bottle = world.object_id("wine_bottle");
    const Eigen::Vector3d p = world.object_pose(world.object_id("rack")).inverse() * world.object_pose(bottle).translation();
    return world.held_object() != bottle && std::abs(p.x()) <= 0.05 && std::abs(p.y()) <= 0.02 &&
           std::abs(p.z() - (kPlate + lying_height())) <= 0.01;
  }

  std::vector<Waypoint> expert_waypoints(const world::World& world) const override {
    const Eigen::Isometry3d bottle = world.object_pose(world.object_id("wine_bottle"));
    const Eigen::Isometry3d rack = world.object_pose(world.object_id("rack"));
    auto waypoints = grasp_at(bottle.translation(), yaw_of(bottle), 0.15);
    const auto place = place_at(rack * Eigen::Vector3d(0, 0, kPlate + lying_height()), yaw_of(rack), 0.12);
    waypoints.insert(waypoints.end(), place.begin(), place.end() - 1);  // no retreat: placed is done
    return waypoints;
  }
};

}  // namespace

std::unique_ptr<Task> make_stack_wine() { return std::make_unique<StackWine>(); }

}  // namespace qte::tasks

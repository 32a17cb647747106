// pick_up_cup: two cups, one of the variation's colour and one of another (RLBench's
// pick_up_cup, 20 colour variations); grasp the cup of the named colour and lift it. Success:
// that cup held and its centre more than 10 cm from where it stood (RLBench: grasped and out
// of a sensor at its start). Sizes are ours: open cups 7 cm across and 9 cm high (floor and a
// wall of 16 pieces), at least 15 cm apart so the open fingers pass beside the other cup.
// The expert: above the cup, grasp it halfway up, lift 15 cm.
#include "tasks/blocks.hpp"
#include "tasks/shapes.hpp"

namespace qte::tasks {
namespace {

constexpr double kRadius = 0.035, kHeight = 0.09, kWall = 0.005;
constexpr double kStartZone = 0.1;

class PickUpCup : public Task {
 public:
  std::string name() const override { return "pick_up_cup"; }
  int variation_count() const override { return static_cast<int>(colours().size()); }
  std::string description(int variation) const override { return "pick up the " + colours()[variation].name + " cup"; }

  void build(world::World& world, int variation, std::mt19937_64& rng) override {
    const auto positions = sample_separated(rng, 2, {kRegionMinX, kRegionMinY, 0}, {kRegionMaxX, kRegionMaxY, 0}, 0.15);
    const int other = pick_distinct(rng, 1, static_cast<int>(colours().size()), variation)[0];
    for (int i = 0; i < 2; ++i) {
      Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();  // the centre of its bottom
      pose.translation() << positions[i].x(), positions[i].y(), world.layout().table_height_m + world::kHullMargin;
      std::vector<Piece> pieces = tube(16, kRadius, kRadius - kWall, 0, kHeight);
      pieces.push_back(frustum(16, kRadius, kRadius, 0, kWall));
      world::ObjectSpec cup = solid(i == 0 ? "cup" : "other_cup", std::move(pieces), pose,
                                    colours()[i == 0 ? variation : other].rgb);
      cup.mass_kg = 0.1;
      cup.graspable = true;
      cup.role = i == 0 ? world::ObjectSpec::Role::target : world::ObjectSpec::Role::distractor;
      cup.grasp_region = Eigen::AlignedBox3d(Eigen::Vector3d(-kRadius, -kRadius, 0), Eigen::Vector3d(kRadius, kRadius, kHeight));
      world.add_object(cup);
      if (i == 0) start_ = pose.translation();
    }
  }

  bool success(const world::World& world) const override {
    const int cup = world.object_id("cup");
    return world.held_object() == cup && (world.object_pose(cup).translation() - start_).norm() > kStartZone;
  }

  std::vector<Waypoint> expert_waypoints(const world::World& world) const override {
    return grasp_at(grasp_point(world, world.object_id("cup")), 0, 0.15);
  }

 private:
  Eigen::Vector3d start_ = Eigen::Vector3d::Zero();  // where the cup stood when the scene was built
};

}  // namespace

std::unique_ptr<Task> make_pick_up_cup() { return std::make_unique<PickUpCup>(); }

}  // namespace qte::tasks

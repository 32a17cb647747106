// stack_blocks: four blocks of the variation's colour and four of one other colour (5 cm, as
// RLBench's), apart on the table, and a flat target plane; stack 2, 3 or 4 of the target
// colour on the plane (RLBench's stack_blocks). Variation v: colour v / 3 of the 20, stack
// height 2 + v % 3 (60 variations). The expert takes six next-best poses a block: above it,
// grasp, lift, above the stack, place (the gripper opens and physics settles the block),
// back up (but after the last: the episode ends at success); 4 blocks need 23, so episodes
// are 30 long, not the published 10.
#include <algorithm>

#include "tasks/blocks.hpp"

namespace qte::tasks {
namespace {

constexpr int kPerColour = 4;
constexpr double kPlaneSize = 0.1;      // the target plane's side
constexpr double kLevelTolerance = 0.01;  // a stacked block's centre within this of its level

class StackBlocks : public Task {
 public:
  std::string name() const override { return "stack_blocks"; }
  int variation_count() const override { return 3 * static_cast<int>(colours().size()); }
  int episode_length() const override { return 30; }
  std::string description(int variation) const override {
    return "stack " + std::to_string(height(variation)) + " " + colours()[variation / 3].name + " blocks";
  }

  void build(world::World& world, int variation, std::mt19937_64& rng) override {
    stack_ = height(variation);
    // Nine places 10 cm apart: too dense for joint rejection sampling, so one at a time.
    const auto positions = place_one_by_one(rng, 2 * kPerColour + 1, {kRegionMinX, kRegionMinY, 0},
                                            {kRegionMaxX, kRegionMaxY, 0}, 0.1);
    const int other = pick_distinct(rng, 1, static_cast<int>(colours().size()), variation / 3)[0];
    std::uniform_real_distribution<double> yaw(-M_PI / 4, M_PI / 4);
    for (int i = 0; i < 2 * kPerColour; ++i) {
      const bool target = i < kPerColour;
      const std::string name = (target ? "target" : "distractor") + std::to_string(i % kPerColour + 1);
      world::ObjectSpec spec = block(world, name, positions[i], yaw(rng), colours()[target ? variation / 3 : other].rgb);
      spec.role = target ? world::ObjectSpec::Role::target : world::ObjectSpec::Role::distractor;
      world.add_object(spec);
    }
    world::ObjectSpec plane;
    plane.name = "target_plane";
    plane.size = Eigen::Vector3d(kPlaneSize, kPlaneSize, 0.002);
    plane.pose.translation() << positions.back().x(), positions.back().y(), world.layout().table_height_m + 0.001;
    plane.mass_kg = 0;
    plane.collides = false;  // drawn on the table; the blocks stand on the table through it
    plane.graspable = false;
    plane.appearance.colour = Eigen::Vector3f(0.9f, 0.9f, 0.9f);
    world.add_object(plane);
  }

  // Target blocks over the plane, from the bottom: one on each level, the stack as high as
  // asked, and nothing held.
  bool success(const world::World& world) const override {
    if (world.held_object() >= 0) return false;
    const Eigen::Vector3d plane = world.object_pose(world.object_id("target_plane")).translation();
    const double table = world.layout().table_height_m;
    std::vector<double> heights;
    for (int i = 1; i <= kPerColour; ++i) {
      const Eigen::Vector3d p = world.object_pose(world.object_id("target" + std::to_string(i))).translation();
      if ((p - plane).head<2>().cwiseAbs().maxCoeff() <= kPlaneSize / 2) heights.push_back(p.z());
    }
    if (static_cast<int>(heights.size()) != stack_) return false;
    std::sort(heights.begin(), heights.end());
    for (int level = 0; level < stack_; ++level)
      if (std::abs(heights[level] - (table + kBlockSize / 2 + level * kBlockSize)) > kLevelTolerance) return false;
    return true;
  }

  std::vector<Waypoint> expert_waypoints(const world::World& world) const override {
    const Eigen::Vector3d plane = world.object_pose(world.object_id("target_plane")).translation();
    const double table = world.layout().table_height_m;
    std::vector<Waypoint> waypoints;
    for (int level = 0; level < stack_; ++level) {
      const int id = world.object_id("target" + std::to_string(level + 1));
      // Above, grasp, lift clear of the stack it will be carried over.
      auto pick = grasp_and_lift(world, id, 0.0);
      pick.back().tcp_pose.translation().z() = table + (stack_ + 1.5) * kBlockSize + 0.05;
      waypoints.insert(waypoints.end(), pick.begin(), pick.end());
      // Above the stack, square to the plane; down to 5 mm above its top; open; back up.
      const auto place = place_at(Eigen::Vector3d(plane.x(), plane.y(), table + kBlockSize / 2 + level * kBlockSize), 0, 0.1);
      waypoints.insert(waypoints.end(), place.begin(), place.end());
    }
    waypoints.pop_back();  // the last release completes the task: the episode ends there
    return waypoints;
  }

 private:
  static int height(int variation) { return 2 + variation % 3; }
  int stack_ = 2;  // of the variation the scene was built for
};

}  // namespace

std::unique_ptr<Task> make_stack_blocks() { return std::make_unique<StackBlocks>(); }

}  // namespace qte::tasks

// reach_prism: three small yellow objects of one height on the table, a pentagonal prism, a
// triangular prism and a cube; bring the gripper to the pentagonal prism (the paper's
// real-world task, simulated). Each footprint fits one 6.25 cm voxel of depth 0 and spans
// several 1.9 cm voxels of depth 1: only the finer depth tells the shapes apart.
#include <cmath>

#include "tasks/catalogue.hpp"
#include "tasks/shapes.hpp"

namespace qte::tasks {
namespace {

constexpr double kHeight = 0.03;
constexpr double kReachAbove = 0.02;   // the reach point: this far above the prism's top face
constexpr double kReachRadius = 0.025;  // success: the TCP within this of the reach point

class ReachPrism : public Task {
 public:
  std::string name() const override { return "reach_prism"; }
  int variation_count() const override { return 1; }
  std::string description(int) const override { return "reach the pentagonal prism"; }

  void build(world::World& world, int, std::mt19937_64& rng) override {
    const auto positions = sample_separated(rng, 3, {kRegionMinX, kRegionMinY, 0}, {kRegionMaxX, kRegionMaxY, 0}, 0.1);
    std::uniform_real_distribution<double> yaw(-M_PI, M_PI);
    // Footprints 4.0-4.3 cm across: the pentagon's 2.1 cm circumradius, the triangle's 2.5 cm
    // (4.3 cm sides), the cube's 3 cm sides (4.2 cm diagonal).
    const Eigen::Vector3f yellow(0.95f, 0.8f, 0.1f);
    auto prism = [&](const std::string& name, int sides, double radius, const Eigen::Vector3d& xy) {
      // Fixed where placed: reaching does not move it.
      world::ObjectSpec spec = standing_prism(world, name, {regular_polygon(sides, radius)}, kHeight, xy, yaw(rng), yellow);
      spec.role = name == "prism" ? world::ObjectSpec::Role::target : world::ObjectSpec::Role::distractor;
      world.add_object(spec);
    };
    prism("prism", 5, 0.021, positions[0]);
    prism("triangular_prism", 3, 0.025, positions[1]);
    prism("cube", 4, 0.03 / std::sqrt(2.0), positions[2]);
  }

  bool success(const world::World& world) const override {
    return (world.tcp_pose().translation() - reach_point(world)).norm() <= kReachRadius;
  }

  std::vector<Waypoint> expert_waypoints(const world::World& world) const override {
    Waypoint reach;
    reach.tcp_pose.linear() = top_down(0);
    reach.tcp_pose.translation() = reach_point(world);
    return {reach};
  }

 private:
  static Eigen::Vector3d reach_point(const world::World& world) {
    return world.object_pose(world.object_id("prism")).translation() +
           Eigen::Vector3d(0, 0, kHeight / 2 + kReachAbove);
  }
};

}  // namespace

std::unique_ptr<Task> make_reach_prism() { return std::make_unique<ReachPrism>(); }

}  // namespace qte::tasks

// lift_numbered_block: three white blocks numbered 1, 2 and 3; lift the one the variation
// names. At 16^3 over a 1 m cube the blocks look alike: this is a "coarse ambiguity" task.
#include "render/textures.hpp"
#include "tasks/blocks.hpp"

namespace qte::tasks {
namespace {

constexpr double kLiftHeight = 0.15;  // above the table, bottom of the block

class LiftNumberedBlock : public Task {
 public:
  std::string name() const override { return "lift_numbered_block"; }
  int variation_count() const override { return 3; }
  std::string description(int variation) const override {
    return "lift the block numbered " + std::to_string(variation + 1);
  }

  void build(world::World& world, int variation, std::mt19937_64& rng) override {
    const auto positions = sample_separated(rng, 3, {kRegionMinX, kRegionMinY, 0},
                                            {kRegionMaxX, kRegionMaxY, 0}, 0.2);
    const Eigen::Vector3f paper(0.95f, 0.95f, 0.95f), ink(0.05f, 0.05f, 0.05f);
    std::uniform_real_distribution<double> yaw(-M_PI / 6, M_PI / 6);
    for (int digit = 1; digit <= 3; ++digit) {
      // Yaw near a quarter turn: the top face's image "up" (object +y) then points away
      // from the front camera, so the digit reads upright in its image.
      world::ObjectSpec spec = block(world, "block" + std::to_string(digit), positions[digit - 1],
                                   M_PI / 2 + yaw(rng), paper);
      const cv::Mat texture = render::text_texture(std::to_string(digit), 64, paper, ink);
      for (int face = 0; face < 5; ++face) spec.appearance.box_face_textures[face] = texture;
      spec.role = digit == variation + 1 ? world::ObjectSpec::Role::target : world::ObjectSpec::Role::distractor;
      world.add_object(spec);
    }
    target_ = "block" + std::to_string(variation + 1);
  }

  bool success(const world::World& world) const override {
    const int target = world.object_id(target_);
    const double bottom = world.object_pose(target).translation().z() - kBlockSize / 2;
    return world.held_object() == target &&
           bottom >= world.layout().table_height_m + kLiftHeight - 0.01;
  }

  std::vector<Waypoint> expert_waypoints(const world::World& world) const override {
    return grasp_and_lift(world, world.object_id(target_), kLiftHeight + 0.02);
  }

 private:
  std::string target_ = "block1";
};

}  // namespace

std::unique_ptr<Task> make_lift_numbered_block() { return std::make_unique<LiftNumberedBlock>(); }

}  // namespace qte::tasks

// take_umbrella_out_of_umbrella_stand: a closed umbrella standing in a stand (RLBench's, one
// variation); grasp it by the handle and lift it out. Success: the umbrella's foot out of the
// stand — above its rim or beside it (RLBench: not inside a sensor in the stand). Sizes are
// ours, scaled to the arm's reach over a table: a 12 cm stand 12 cm across, a 30 cm umbrella
// (foot, furled canopy 6 cm across, shaft, a 2.6 cm handle 5 cm long). The umbrella's origin
// is its foot, where its mass is, so it stands upright in the stand. The expert: above the
// handle, grasp it, lift 14 cm (its foot 2 cm over the rim).
#include "tasks/blocks.hpp"
#include "tasks/shapes.hpp"

namespace qte::tasks {
namespace {

constexpr double kStandRadius = 0.06, kStandHeight = 0.12, kStandWall = 0.008, kStandFloor = 0.01;
constexpr double kHandleRadius = 0.013, kHandleBottom = 0.25, kHandleTop = 0.3;

std::vector<Piece> umbrella() {
  return {frustum(12, 0.02, 0.012, 0, 0.02),                       // the foot, flat and wide: it stands
          frustum(12, 0.01, 0.03, 0.02, 0.08),                     // the furled canopy, widening
          frustum(12, 0.03, 0.008, 0.08, 0.22),                    // and narrowing to the shaft
          frustum(8, 0.006, 0.006, 0.22, kHandleBottom),          // the shaft
          frustum(12, kHandleRadius, kHandleRadius, kHandleBottom, kHandleTop)};  // the handle
}

class TakeUmbrellaOutOfUmbrellaStand : public Task {
 public:
  std::string name() const override { return "take_umbrella_out_of_umbrella_stand"; }
  int variation_count() const override { return 1; }
  std::string description(int) const override { return "take umbrella out of umbrella stand"; }

  void build(world::World& world, int, std::mt19937_64& rng) override {
    // Within the arm's reach of the lifted handle (45 cm over the table), not the region's far
    // corners; and 12 cm from under the gripper's ready pose, which the handle would reach.
    Eigen::Vector3d ready = world.tcp_pose().translation();
    ready.z() = 0;
    const Eigen::Vector3d xy = sample_away_from(rng, {ready}, {0.05, -0.15, 0}, {0.2, 0.15, 0}, 0.12);
    Eigen::Isometry3d stand = Eigen::Isometry3d::Identity();  // the centre of its underside
    stand.translation() << xy.x(), xy.y(), world.layout().table_height_m;
    std::vector<Piece> pieces = tube(16, kStandRadius, kStandRadius - kStandWall, 0, kStandHeight);
    pieces.push_back(frustum(16, kStandRadius, kStandRadius, 0, kStandFloor));
    world.add_object(solid("umbrella_stand", std::move(pieces), stand, {0.2f, 0.25f, 0.45f}));

    Eigen::Isometry3d pose = stand;  // standing on the stand's floor, turned at random
    pose.linear() = Eigen::AngleAxisd(uniform(rng, -M_PI, M_PI), Eigen::Vector3d::UnitZ()).toRotationMatrix();
    pose.translation().z() += kStandFloor + 2 * world::kHullMargin;
    world::ObjectSpec spec = solid("umbrella", umbrella(), pose, {0.55f, 0.1f, 0.15f});
    spec.mass_kg = 0.3;
    spec.graspable = true;
    spec.role = world::ObjectSpec::Role::target;
    spec.grasp_region = Eigen::AlignedBox3d(Eigen::Vector3d(-kHandleRadius, -kHandleRadius, kHandleBottom),
                                            Eigen::Vector3d(kHandleRadius, kHandleRadius, kHandleTop));
    world.add_object(spec);
  }

  bool success(const world::World& world) const override {
    const Eigen::Vector3d foot = world.object_pose(world.object_id("umbrella_stand")).inverse() *
                                 world.object_pose(world.object_id("umbrella")).translation();
    return foot.z() > kStandHeight || foot.head<2>().norm() > kStandRadius;
  }

  std::vector<Waypoint> expert_waypoints(const world::World& world) const override {
    return grasp_at(grasp_point(world, world.object_id("umbrella")), 0, 0.14);
  }
};

}  // namespace

std::unique_ptr<Task> make_take_umbrella_out_of_umbrella_stand() {
  return std::make_unique<TakeUmbrellaOutOfUmbrellaStand>();
}

}  // namespace qte::tasks

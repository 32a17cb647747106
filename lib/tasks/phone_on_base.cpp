// phone_on_base: a phone lying on the table and its base (RLBench's phone_on_base, one
// variation); put the phone on the base and let go. Success: the phone resting on the base's
// top, its centre within 2 x 3 cm of the base's, nothing held (RLBench: inside a sensor on
// the base, nothing grasped). Sizes are ours: a 7 x 14 x 1 cm phone, grasped across its width;
// a 10 x 18 x 1.5 cm base. Both yaws within +-45 degrees. At 6.25 cm the 1 cm phone is a thin
// layer over the table in its voxels. The expert: above the phone, grasp, lift, over the base
// square to it, down to 5 mm above resting, let go.
#include "tasks/blocks.hpp"

namespace qte::tasks {
namespace {

const Eigen::Vector3d kPhone(0.07, 0.14, 0.01), kBase(0.1, 0.18, 0.015);

class PhoneOnBase : public Task {
 public:
  std::string name() const override { return "phone_on_base"; }
  int variation_count() const override { return 1; }
  std::string description(int) const override { return "put the phone on the base"; }

  void build(world::World& world, int, std::mt19937_64& rng) override {
    const double table = world.layout().table_height_m, side = uniform(rng, 0, 1) < 0.5 ? -1 : 1;
    auto box = [&](const std::string& name, const Eigen::Vector3d& size, double y, const Eigen::Vector3f& colour) {
      world::ObjectSpec spec;
      spec.name = name;
      spec.size = size;
      spec.pose.linear() = Eigen::AngleAxisd(uniform(rng, -M_PI / 4, M_PI / 4), Eigen::Vector3d::UnitZ()).toRotationMatrix();
      spec.pose.translation() << uniform(rng, 0.05, 0.25), y, table + size.z() / 2;
      spec.appearance.colour = colour;
      return spec;
    };
    world::ObjectSpec base = box("base", kBase, side * uniform(rng, 0.1, 0.18), {0.8f, 0.8f, 0.85f});
    base.mass_kg = 0;
    base.graspable = false;
    world.add_object(base);
    world::ObjectSpec phone = box("phone", kPhone, -side * uniform(rng, 0.08, 0.18), {0.08f, 0.08f, 0.12f});
    phone.mass_kg = 0.15;
    phone.role = world::ObjectSpec::Role::target;
    world.add_object(phone);
  }

  bool success(const world::World& world) const override {
    const int phone = world.object_id("phone");
    const Eigen::Vector3d p = world.object_pose(world.object_id("base")).inverse() * world.object_pose(phone).translation();
    return world.held_object() < 0 && std::abs(p.x()) <= 0.02 && std::abs(p.y()) <= 0.03 &&
           std::abs(p.z() - (kBase.z() + kPhone.z()) / 2) <= 0.005;
  }

  // TCP x along each box's long (y) axis, so the fingers close across the phone's width.
  std::vector<Waypoint> expert_waypoints(const world::World& world) const override {
    const Eigen::Isometry3d phone = world.object_pose(world.object_id("phone"));
    const Eigen::Isometry3d base = world.object_pose(world.object_id("base"));
    // The long axis's own direction, 45..135 degrees for the boxes' yaws: folded into +-90 (the
    // gripper is symmetric) the grasp's yaw would jump from +90 to -90 as the phone turns past 0,
    // a rotation target no network can follow from a few demonstrations.
    auto long_axis_yaw = [](const Eigen::Isometry3d& pose) { return std::atan2(pose.linear()(1, 1), pose.linear()(0, 1)); };
    auto waypoints = grasp_at(phone.translation(), long_axis_yaw(phone), 0.12);
    const auto place = place_at(base * Eigen::Vector3d(0, 0, (kBase.z() + kPhone.z()) / 2), long_axis_yaw(base), 0.1);
    waypoints.insert(waypoints.end(), place.begin(), place.end() - 1);  // no retreat: placed is done
    return waypoints;
  }
};

}  // namespace

std::unique_ptr<Task> make_phone_on_base() { return std::make_unique<PhoneOnBase>(); }

}  // namespace qte::tasks

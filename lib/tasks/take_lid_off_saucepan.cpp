// take_lid_off_saucepan: a saucepan with its lid on (RLBench's take_lid_off_saucepan); grasp
// the lid by its knob and lift it off. Success: the lid held and at least 10 cm above the
// pan's rim (RLBench: grasped and inside a sensor above the pan). One variation. Sizes are
// ours (RLBench's meshes are not at hand): a 17 cm pan, 7 cm deep, with a 12 cm handle, and a
// lid whose knob is 2.4 cm across and 2.5 cm high — a knob a 6.25 cm voxel holds together
// with the lid under it, so only the finer depths find it. The pan's place and yaw (where
// its handle points) are random. The expert: above the knob, grasp it, lift 20 cm.
#include "tasks/blocks.hpp"
#include "tasks/shapes.hpp"

namespace qte::tasks {
namespace {

constexpr double kPanRadius = 0.085, kPanHeight = 0.07, kWall = 0.008, kFloor = 0.01;
constexpr double kLidRadius = 0.088, kLidThickness = 0.008;
constexpr double kKnobRadius = 0.012, kKnobHeight = 0.025;
constexpr double kLiftedAboveRim = 0.1;

class TakeLidOffSaucepan : public Task {
 public:
  std::string name() const override { return "take_lid_off_saucepan"; }
  int variation_count() const override { return 1; }
  std::string description(int) const override { return "take lid off the saucepan"; }

  void build(world::World& world, int, std::mt19937_64& rng) override {
    const double table = world.layout().table_height_m;
    // The pan: floor, wall and handle, its origin at the centre of its bottom.
    Eigen::Isometry3d pan = Eigen::Isometry3d::Identity();
    pan.linear() = Eigen::AngleAxisd(uniform(rng, -M_PI, M_PI), Eigen::Vector3d::UnitZ()).toRotationMatrix();
    pan.translation() << uniform(rng, 0.05, 0.25), uniform(rng, -0.15, 0.15), table;
    std::vector<Piece> pieces = tube(16, kPanRadius, kPanRadius - kWall, 0, kPanHeight);
    pieces.push_back(frustum(16, kPanRadius, kPanRadius, 0, kFloor));
    pieces.push_back(box_piece({kPanRadius - 0.002, -0.012, kPanHeight - 0.02}, {kPanRadius + 0.12, 0.012, kPanHeight - 0.005}));
    world.add_object(solid("saucepan", std::move(pieces), pan, {0.35f, 0.35f, 0.38f}));

    // The lid on the rim, its origin at the centre of its underside: disc and knob.
    Eigen::Isometry3d lid = pan;
    lid.translation().z() += kPanHeight + 2 * world::kHullMargin;
    world::ObjectSpec spec = solid("lid", {frustum(24, kLidRadius, kLidRadius, 0, kLidThickness),
                                           frustum(12, kKnobRadius, kKnobRadius, kLidThickness, kLidThickness + kKnobHeight)},
                                   lid, {0.75f, 0.75f, 0.8f});
    spec.mass_kg = 0.2;
    spec.graspable = true;
    spec.role = world::ObjectSpec::Role::target;
    spec.grasp_region = Eigen::AlignedBox3d(Eigen::Vector3d(-kKnobRadius, -kKnobRadius, kLidThickness),
                                            Eigen::Vector3d(kKnobRadius, kKnobRadius, kLidThickness + kKnobHeight));
    world.add_object(spec);
  }

  bool success(const world::World& world) const override {
    const int lid = world.object_id("lid");
    const double rim = world.object_pose(world.object_id("saucepan")).translation().z() + kPanHeight;
    return world.held_object() == lid && world.object_pose(lid).translation().z() >= rim + kLiftedAboveRim;
  }

  std::vector<Waypoint> expert_waypoints(const world::World& world) const override {
    return grasp_at(grasp_point(world, world.object_id("lid")), 0, 0.2);
  }
};

}  // namespace

std::unique_ptr<Task> make_take_lid_off_saucepan() { return std::make_unique<TakeLidOffSaucepan>(); }

}  // namespace qte::tasks

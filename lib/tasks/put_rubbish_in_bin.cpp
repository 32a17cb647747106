// put_rubbish_in_bin: a crumpled piece of rubbish and two tomatoes on the table, and a bin
// (RLBench's put_rubbish_in_bin, one variation); put the rubbish in the bin, leaving the
// tomatoes. Success: the rubbish's centre inside the bin, below its rim. RLBench lays the
// three out in fixed places and swaps the rubbish with one tomato; ours are drawn anywhere
// in the region, which covers the swap. Sizes are ours: rubbish about 4.5 cm across and 3 cm
// high (an irregular hull with a flat underside, so it rests still), tomatoes 6 cm across and
// 5 cm high, a 20 x 16 cm bin 12 cm high on one side of the table. At 6.25 cm the rubbish
// and a tomato are one voxel each, told apart by colour and shape only. The expert: above the
// rubbish, grasp, lift 15 cm, over the bin and let go (physics drops it in).
#include "tasks/blocks.hpp"
#include "tasks/shapes.hpp"

namespace qte::tasks {
namespace {

const Eigen::Vector3d kBinSize(0.2, 0.16, 0.12);
constexpr double kBinWall = 0.01;

// A crumpled ball of paper: two irregular octagons, 3 cm apart, joined by a bulging middle.
Piece crumpled() {
  const double bottom[] = {0.018, 0.022, 0.016, 0.02, 0.019, 0.015, 0.021, 0.017};
  const double middle[] = {0.024, 0.019, 0.023, 0.021, 0.017, 0.024, 0.02, 0.022};
  const double top[] = {0.014, 0.017, 0.012, 0.016, 0.015, 0.011, 0.016, 0.013};
  Piece piece;
  for (int i = 0; i < 8; ++i) {
    const double a = 2 * M_PI * i / 8;
    piece.emplace_back(bottom[i] * std::cos(a), bottom[i] * std::sin(a), -0.015);
    piece.emplace_back(middle[i] * std::cos(a + 0.3), middle[i] * std::sin(a + 0.3), 0.002 * (i % 3) - 0.002);
    piece.emplace_back(top[i] * std::cos(a + 0.5), top[i] * std::sin(a + 0.5), 0.015 - 0.002 * (i % 2));
  }
  return piece;
}

// A tomato: an ellipsoid 6 cm across and 5.4 cm high, cut flat 2.2 cm under its centre.
Piece tomato() {
  constexpr double kRadius = 0.03, kHalfHeight = 0.027, kCut = -0.022;
  Piece piece{{0, 0, kHalfHeight}};
  auto ring = [&](double r, double z) {
    for (int i = 0; i < 12; ++i)
      piece.emplace_back(r * std::cos(2 * M_PI * i / 12), r * std::sin(2 * M_PI * i / 12), z);
  };
  for (double polar : {M_PI / 4, M_PI / 2, 3 * M_PI / 4}) ring(kRadius * std::sin(polar), kHalfHeight * std::cos(polar));
  ring(kRadius * std::sqrt(1 - (kCut / kHalfHeight) * (kCut / kHalfHeight)), kCut);
  return piece;
}

class PutRubbishInBin : public Task {
 public:
  std::string name() const override { return "put_rubbish_in_bin"; }
  int variation_count() const override { return 1; }
  std::string description(int) const override { return "put rubbish in bin"; }

  void build(world::World& world, int, std::mt19937_64& rng) override {
    const double table = world.layout().table_height_m;
    // The bin on one side (its origin: the centre of its floor's underside), the rest on the other.
    const double side = uniform(rng, 0, 1) < 0.5 ? -1 : 1;
    Eigen::Isometry3d bin = Eigen::Isometry3d::Identity();
    bin.linear() = Eigen::AngleAxisd(uniform(rng, -0.3, 0.3), Eigen::Vector3d::UnitZ()).toRotationMatrix();
    bin.translation() << uniform(rng, 0.1, 0.2), side * uniform(rng, 0.14, 0.2), table;
    const Eigen::Vector3d h = kBinSize / 2;
    world.add_object(solid("bin", {box_piece({-h.x(), -h.y(), 0}, {h.x(), h.y(), kBinWall}),
                                   box_piece({-h.x(), -h.y(), 0}, {-h.x() + kBinWall, h.y(), kBinSize.z()}),
                                   box_piece({h.x() - kBinWall, -h.y(), 0}, {h.x(), h.y(), kBinSize.z()}),
                                   box_piece({-h.x(), -h.y(), 0}, {h.x(), -h.y() + kBinWall, kBinSize.z()}),
                                   box_piece({-h.x(), h.y() - kBinWall, 0}, {h.x(), h.y(), kBinSize.z()})},
                           bin, {0.25f, 0.3f, 0.3f}));

    const double y_lo = side > 0 ? kRegionMinY : -0.05, y_hi = side > 0 ? 0.05 : kRegionMaxY;
    const auto places = sample_separated(rng, 3, {kRegionMinX, y_lo, 0}, {kRegionMaxX, y_hi, 0}, 0.1);
    std::uniform_real_distribution<double> yaw(-M_PI, M_PI);
    auto resting = [&](const Eigen::Vector3d& xy, double lowest) {
      Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
      pose.linear() = Eigen::AngleAxisd(yaw(rng), Eigen::Vector3d::UnitZ()).toRotationMatrix();
      pose.translation() << xy.x(), xy.y(), table - lowest + world::kHullMargin;
      return pose;
    };
    world::ObjectSpec rubbish = solid("rubbish", {crumpled()}, resting(places[0], -0.015), {0.9f, 0.9f, 0.84f});
    rubbish.mass_kg = 0.02;
    rubbish.graspable = true;
    rubbish.role = world::ObjectSpec::Role::target;
    world.add_object(rubbish);
    for (int i = 1; i <= 2; ++i) {
      world::ObjectSpec t = solid("tomato" + std::to_string(i), {tomato()}, resting(places[i], -0.022), {0.85f, 0.1f, 0.05f});
      t.mass_kg = 0.1;
      t.role = world::ObjectSpec::Role::distractor;  // graspable-looking, not to be binned
      world.add_object(t);
    }
  }

  bool success(const world::World& world) const override {
    const Eigen::Vector3d p = world.object_pose(world.object_id("bin")).inverse() *
                              world.object_pose(world.object_id("rubbish")).translation();
    const Eigen::Vector3d inner = kBinSize / 2 - Eigen::Vector3d::Constant(kBinWall);
    return std::abs(p.x()) <= inner.x() && std::abs(p.y()) <= inner.y() && p.z() >= 0 && p.z() <= kBinSize.z();
  }

  std::vector<Waypoint> expert_waypoints(const world::World& world) const override {
    const Eigen::Isometry3d rubbish = world.object_pose(world.object_id("rubbish"));
    auto waypoints = grasp_at(rubbish.translation(), yaw_of(rubbish), 0.15);
    Waypoint over_bin = waypoints.back();
    over_bin.tcp_pose.translation() = world.object_pose(world.object_id("bin")) * Eigen::Vector3d(0, 0, kBinSize.z() + 0.1);
    over_bin.ignore_collisions = false;
    over_bin.gripper_open = true;  // let go over the bin
    waypoints.push_back(over_bin);
    return waypoints;
  }
};

}  // namespace

std::unique_ptr<Task> make_put_rubbish_in_bin() { return std::make_unique<PutRubbishInBin>(); }

}  // namespace qte::tasks

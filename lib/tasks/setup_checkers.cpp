// setup_checkers: a checkers board (8 x 8 squares of 4 cm) set up with 12 red and 12 black
// checkers (r 1.79 cm, h 0.72 cm, RLBench's), except 1, 2 or 3 of them (the variation) that
// lie stacked beside the board at a board-relative spot; put each back on its square
// (RLBench's setup_checkers). The board's pose is random within a few centimetres and
// degrees, which checkers are off it too. The expert takes six next-best poses a checker
// (above the stack, grasp, lift, above its square, place: the gripper opens and physics
// settles it, back up, but not after the last); 3 checkers need 17, so episodes are 25 long.
#include <algorithm>
#include <cmath>

#include "render/textures.hpp"
#include "tasks/blocks.hpp"
#include "tasks/shapes.hpp"

namespace qte::tasks {
namespace {

constexpr double kSquare = 0.04, kBoardThickness = 0.01;
constexpr double kCheckerRadius = 0.0179, kCheckerHeight = 0.0072;
constexpr double kHomeTolerance = 0.01;  // a checker's centre within this of its square's (xy)
constexpr double kAbove = 0.1;           // approach and carry height over the board

class SetupCheckers : public Task {
 public:
  std::string name() const override { return "setup_checkers"; }
  int variation_count() const override { return 3; }
  int episode_length() const override { return 25; }
  std::string description(int variation) const override {
    return "place the " + std::to_string(variation + 1) + " checker" + (variation ? "s" : "") + " on the board";
  }

  void build(world::World& world, int variation, std::mt19937_64& rng) override {
    const double table = world.layout().table_height_m;
    Eigen::Isometry3d board = Eigen::Isometry3d::Identity();
    board.linear() = Eigen::AngleAxisd(uniform(rng, -0.15, 0.15), Eigen::Vector3d::UnitZ()).toRotationMatrix();
    board.translation() << uniform(rng, 0.10, 0.14), uniform(rng, -0.03, 0.03), table + kBoardThickness / 2;
    world::ObjectSpec spec;
    spec.name = "board";
    spec.size = Eigen::Vector3d(8 * kSquare, 8 * kSquare, kBoardThickness);
    spec.pose = board;
    spec.mass_kg = 0;
    spec.graspable = false;
    spec.appearance.colour = Eigen::Vector3f(0.93f, 0.87f, 0.72f);
    spec.appearance.box_face_textures[4] = render::checkerboard_texture(8, spec.appearance.colour, {0.15f, 0.35f, 0.2f});
    world.add_object(spec);

    // The opening position: each side's 12 on the dark squares of its three home rows.
    homes_.clear();
    for (int row : {0, 1, 2, 5, 6, 7})
      for (int column = 0; column < 8; ++column)
        if ((row + column) % 2 == 0) {
          const Eigen::Vector3d square((column - 3.5) * kSquare, (row - 3.5) * kSquare,
                                       kBoardThickness / 2 + world::kHullMargin + kCheckerHeight / 2);
          homes_.push_back({(row < 4 ? "red" : "black") + std::to_string(homes_.size() % 12), square});
        }
    std::vector<int> order(homes_.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
    std::shuffle(order.begin(), order.end(), rng);
    off_board_.assign(order.begin(), order.begin() + variation + 1);
    // The stack beside the board, 5 cm past its +y edge (board frame), on the table.
    const Eigen::Vector3d spot = board * Eigen::Vector3d(0, 4 * kSquare + 0.05, -kBoardThickness / 2);
    for (std::size_t i = 0; i < homes_.size(); ++i) {
      // A 24-sided prism rather than Bullet's cylinder: thin cylinders stacked on one
      // another slide apart in Bullet within a second (their margin is 0.36 mm); hulls rest.
      world::ObjectSpec checker = standing_prism(world, homes_[i].first, {regular_polygon(24, kCheckerRadius)},
                                               kCheckerHeight, Eigen::Vector3d::Zero(), 0, Eigen::Vector3f::Zero());
      checker.pose.linear() = board.linear();
      const auto stacked = std::find(off_board_.begin(), off_board_.end(), static_cast<int>(i));
      checker.pose.translation() = stacked == off_board_.end()
          ? board * homes_[i].second
          : spot + Eigen::Vector3d(0, 0, (stacked - off_board_.begin()) * (kCheckerHeight + 2 * world::kHullMargin) +
                                               world::kHullMargin + kCheckerHeight / 2);
      checker.mass_kg = 0.01;
      checker.graspable = true;
      // The checkers to move; those already on their squares look just like them.
      checker.role = stacked == off_board_.end() ? world::ObjectSpec::Role::distractor : world::ObjectSpec::Role::target;
      checker.appearance.colour = homes_[i].first[0] == 'r' ? Eigen::Vector3f(0.8f, 0.1f, 0.1f) : Eigen::Vector3f(0.12f, 0.12f, 0.12f);
      world.add_object(checker);
    }
  }

  // Every checker resting on its own square, nothing held.
  bool success(const world::World& world) const override {
    if (world.held_object() >= 0) return false;
    const Eigen::Isometry3d board = world.object_pose(world.object_id("board"));
    for (const auto& [name, square] : homes_) {
      const Eigen::Vector3d at = board.inverse() * world.object_pose(world.object_id(name)).translation();
      if ((at - square).head<2>().norm() > kHomeTolerance || std::abs(at.z() - square.z()) > 0.003) return false;
    }
    return true;
  }

  std::vector<Waypoint> expert_waypoints(const world::World& world) const override {
    const Eigen::Isometry3d board = world.object_pose(world.object_id("board"));
    const double yaw = std::atan2(board.linear()(1, 0), board.linear()(0, 0));
    std::vector<Waypoint> waypoints;
    // From the top of the stack down.
    for (auto i = off_board_.rbegin(); i != off_board_.rend(); ++i) {
      auto pick = grasp_and_lift(world, world.object_id(homes_[*i].first), kAbove);
      const auto place = place_at(board * homes_[*i].second, yaw, kAbove);
      waypoints.insert(waypoints.end(), pick.begin(), pick.end());
      waypoints.insert(waypoints.end(), place.begin(), place.end());
    }
    waypoints.pop_back();  // the last release completes the task: the episode ends there
    return waypoints;
  }

 private:
  std::vector<std::pair<std::string, Eigen::Vector3d>> homes_;  // name, square centre (board frame)
  std::vector<int> off_board_;  // indices into homes_, from the bottom of the stack up
};

}  // namespace

std::unique_ptr<Task> make_setup_checkers() { return std::make_unique<SetupCheckers>(); }

}  // namespace qte::tasks

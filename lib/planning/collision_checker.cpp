#include "planning/collision_checker.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

namespace qte::planning {

namespace {

// The spheres over-cover the links: two spheres of links that may not touch collide only when
// they overlap by more than this.
constexpr double kSelfCollisionMargin_m = 0.01;

}  // namespace

CollisionChecker::CollisionChecker(const RobotSpheres& spheres, const Eigen::Isometry3d& world_from_base,
                                   CollisionCheckOptions options)
    : spheres_(spheres), world_from_base_(world_from_base), options_(options) {}

bool CollisionChecker::state_valid(const robot::JointVector& q, double opening_m, const OccupancyScene* scene) const {
  thread_local std::vector<Sphere> placed;
  spheres_.place(q, opening_m, world_from_base_, placed);
  if (spheres_.self_collision(placed, kSelfCollisionMargin_m)) return false;
  for (const Sphere& s : placed)  // the base link (0) stands on the table
    if (s.link != 0 && s.centre.z() - s.radius_m < options_.table_height_m - kSphereOvercover_m) return false;
  return !scene || !scene->collides(placed, options_.clearance_m);
}

bool CollisionChecker::motion_valid(const robot::JointVector& a, const robot::JointVector& b, double opening_m,
                                    const OccupancyScene* scene) const {
  const int steps = std::max(1, static_cast<int>(std::ceil((b - a).cwiseAbs().maxCoeff() / options_.check_step_rad)));
  for (int i = 1; i <= steps; ++i)
    if (!state_valid(a + (b - a) * (static_cast<double>(i) / steps), opening_m, scene)) return false;
  return true;
}

}  // namespace qte::planning

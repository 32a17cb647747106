// Small prisms standing on the table, made from their footprints: the look-alike objects of
// reach_prism and pick_and_lift_small. A footprint is a set of convex polygons in the object's
// xy plane (centred on its bounding box, which the gripper's grasp test assumes); one polygon
// becomes a convex hull, several a compound that Bullet collides and the cameras see exactly.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "world/world.hpp"

namespace qte::tasks {

using Polygon = std::vector<Eigen::Vector2d>;

// `sides` vertices on a circle of `radius`, the first on the x axis.
Polygon regular_polygon(int sides, double radius);
// A star of `points` tips at `outer` radius and notches at `inner`, as one convex kite per tip
// (centre, notch, tip, notch).
std::vector<Polygon> star_pieces(int points, double outer, double inner);
// A crescent: the disc of `radius` less the same disc shifted by `offset` along +x, cut into
// `slices` strips across y (each a trapezoid, so convex), centred on its bounding box.
std::vector<Polygon> crescent_pieces(double radius, double offset, int slices);

// The prism of `height` over `footprint` standing on the table at (x, y) with yaw `yaw_rad`;
// static and not graspable until the caller says otherwise.
world::ObjectSpec standing_prism(const world::World& world, const std::string& name,
                               const std::vector<Polygon>& footprint, double height,
                               const Eigen::Vector3d& xy, double yaw_rad, const Eigen::Vector3f& colour);

}  // namespace qte::tasks

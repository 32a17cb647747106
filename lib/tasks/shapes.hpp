// Objects made of convex pieces. Small prisms standing on the table, made from their
// footprints: the look-alike objects of reach_prism and pick_and_lift_small. A footprint is a
// set of convex polygons in the object's xy plane (centred on its bounding box, which the
// gripper's grasp test assumes); one polygon becomes a convex hull, several a compound that
// Bullet collides and the cameras see exactly. And the pieces of vessels, stands and bottles
// (Task Set 1): frustums, tubes and boxes.
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

// A convex piece: the vertices of its hull, in the object frame.
using Piece = std::vector<Eigen::Vector3d>;

// The prism over `polygon` from z0 to z1.
Piece extrude(const Polygon& polygon, double z0, double z1);
// A regular `sides`-gon about z widening (or narrowing) from radius r0 at z0 to r1 at z1; a
// flat side, not a corner, towards -y (and +y), so that one lying on its side rests on a face.
Piece frustum(int sides, double r0, double r1, double z0, double z1);
// The box [lo, hi].
Piece box_piece(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi);
// The wall of a tube about z between radii `inner` and `outer`, z0 to z1, as `segments` convex
// pieces (a cup's, a pan's, a stand's wall).
std::vector<Piece> tube(int segments, double outer, double inner, double z0, double z1);
// `pieces` rotated by `rotation` about the object's origin (e.g. a bottle laid along x).
std::vector<Piece> rotated(std::vector<Piece> pieces, const Eigen::Matrix3d& rotation);

// An object of convex pieces (one: a convex hull; several: a compound) at `pose`; static and
// not graspable until the caller says otherwise.
world::ObjectSpec solid(const std::string& name, std::vector<Piece> pieces, const Eigen::Isometry3d& pose,
                        const Eigen::Vector3f& colour);

// The prism of `height` over `footprint` standing on the table at (x, y) with yaw `yaw_rad`;
// static and not graspable until the caller says otherwise.
world::ObjectSpec standing_prism(const world::World& world, const std::string& name,
                               const std::vector<Polygon>& footprint, double height,
                               const Eigen::Vector3d& xy, double yaw_rad, const Eigen::Vector3f& colour);

}  // namespace qte::tasks

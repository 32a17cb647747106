#include "tasks/shapes.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

namespace qte::tasks {

Polygon regular_polygon(int sides, double radius) {
  Polygon polygon;
  for (int i = 0; i < sides; ++i) {
    const double angle = 2 * M_PI * i / sides;
    polygon.emplace_back(radius * std::cos(angle), radius * std::sin(angle));
  }
  return polygon;
}

std::vector<Polygon> star_pieces(int points, double outer, double inner) {
  auto at = [](double radius, double angle) { return Eigen::Vector2d(radius * std::cos(angle), radius * std::sin(angle)); };
  const double step = 2 * M_PI / points;
  std::vector<Polygon> pieces;
  for (int i = 0; i < points; ++i) {
    const double tip = M_PI / 2 + i * step;
    pieces.push_back({Eigen::Vector2d::Zero(), at(inner, tip - step / 2), at(outer, tip), at(inner, tip + step / 2)});
  }
  return pieces;
}

std::vector<Polygon> crescent_pieces(double radius, double offset, int slices) {
  // Across y, the crescent is x in [-s, min(s, offset - s)] with s = sqrt(r^2 - y^2).
  auto section = [&](double y) {
    const double s = std::sqrt(std::max(0.0, radius * radius - y * y));
    return std::pair(Eigen::Vector2d(-s, y), Eigen::Vector2d(std::min(s, offset - s), y));
  };
  std::vector<Polygon> pieces;
  double low = 0, high = 0;  // the strips' extent in x
  for (int i = 0; i < slices; ++i) {
    // Even steps in angle: finer strips where the outline curves fastest, at the tips.
    const double y0 = radius * std::sin(-M_PI / 2 + M_PI * i / slices);
    const double y1 = radius * std::sin(-M_PI / 2 + M_PI * (i + 1) / slices);
    const auto [a0, b0] = section(y0);
    const auto [a1, b1] = section(y1);
    pieces.push_back({a0, b0, b1, a1});
    low = std::min({low, a0.x(), a1.x()});
    high = std::max({high, b0.x(), b1.x()});
  }
  for (Polygon& piece : pieces)
    for (Eigen::Vector2d& p : piece) p.x() -= (low + high) / 2;
  return pieces;
}

Piece extrude(const Polygon& polygon, double z0, double z1) {
  Piece piece;
  for (double z : {z0, z1})
    for (const Eigen::Vector2d& p : polygon) piece.emplace_back(p.x(), p.y(), z);
  return piece;
}

Piece frustum(int sides, double r0, double r1, double z0, double z1) {
  Piece piece;
  for (const auto& [r, z] : {std::pair(r0, z0), std::pair(r1, z1)})
    for (int i = 0; i < sides; ++i) {
      const double angle = 2 * M_PI * (i + 0.5) / sides;  // half a step off the axes: flat sides at +-y
      piece.emplace_back(r * std::cos(angle), r * std::sin(angle), z);
    }
  return piece;
}

Piece box_piece(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  return extrude({{lo.x(), lo.y()}, {hi.x(), lo.y()}, {hi.x(), hi.y()}, {lo.x(), hi.y()}}, lo.z(), hi.z());
}

std::vector<Piece> tube(int segments, double outer, double inner, double z0, double z1) {
  std::vector<Piece> pieces;
  for (int i = 0; i < segments; ++i) {
    const double a0 = 2 * M_PI * i / segments, a1 = 2 * M_PI * (i + 1) / segments;
    Polygon wall;
    for (const auto& [r, a] : {std::pair(inner, a0), std::pair(outer, a0), std::pair(outer, a1), std::pair(inner, a1)})
      wall.emplace_back(r * std::cos(a), r * std::sin(a));
    pieces.push_back(extrude(wall, z0, z1));
  }
  return pieces;
}

std::vector<Piece> rotated(std::vector<Piece> pieces, const Eigen::Matrix3d& rotation) {
  for (Piece& piece : pieces)
    for (Eigen::Vector3d& p : piece) p = rotation * p;
  return pieces;
}

world::ObjectSpec solid(const std::string& name, std::vector<Piece> pieces, const Eigen::Isometry3d& pose,
                        const Eigen::Vector3f& colour) {
  world::ObjectSpec spec;
  spec.name = name;
  if (pieces.size() == 1) {
    spec.shape = world::ObjectSpec::Shape::convex_hull;
    spec.hull_points = std::move(pieces.front());
  } else {
    spec.shape = world::ObjectSpec::Shape::compound;
    spec.pieces = std::move(pieces);
  }
  spec.pose = pose;
  spec.mass_kg = 0;
  spec.graspable = false;
  spec.appearance.colour = colour;
  return spec;
}

world::ObjectSpec standing_prism(const world::World& world, const std::string& name,
                               const std::vector<Polygon>& footprint, double height,
                               const Eigen::Vector3d& xy, double yaw_rad, const Eigen::Vector3f& colour) {
  std::vector<Piece> pieces;
  for (const Polygon& polygon : footprint) pieces.push_back(extrude(polygon, -height / 2, height / 2));
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  pose.translation() << xy.x(), xy.y(), world.layout().table_height_m + height / 2;
  return solid(name, std::move(pieces), pose, colour);
}

}  // namespace qte::tasks

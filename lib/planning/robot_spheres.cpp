#include "planning/robot_spheres.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "common/error.hpp"

namespace qte::planning {
namespace {

// Spheres covering one primitive, in the primitive's own frame (centred on it).
// Each sphere circumscribes a slice or sub-box of the primitive, so together they cover all
// of it: a sphere of the primitive's own radius would leave the cylinder's rim uncovered
// between sphere centres.
std::vector<std::pair<Eigen::Vector3d, double>> cover(const robot::Shape& shape) {
  std::vector<std::pair<Eigen::Vector3d, double>> spheres;
  switch (shape.kind) {
    case robot::Shape::Kind::sphere:
      spheres.emplace_back(Eigen::Vector3d::Zero(), shape.size.x());
      break;
    case robot::Shape::Kind::cylinder: {
      // Slices along z no longer than the radius: radius grows by at most 12%.
      const double r = shape.size.x(), length = shape.size.y();
      const int n = std::max(1, static_cast<int>(std::ceil(length / r - 1e-9)));
      const double slice = length / n;
      const double radius = std::hypot(r, slice / 2);
      for (int i = 0; i < n; ++i)
        spheres.emplace_back(Eigen::Vector3d(0, 0, -length / 2 + slice * (i + 0.5)), radius);
      break;
    }
    case robot::Shape::Kind::box: {
      // Roughly cubic sub-boxes with the side of the smallest extent.
      const Eigen::Vector3d extent = shape.size;
      const double side = extent.minCoeff();
      Eigen::Vector3i n;
      for (int k = 0; k < 3; ++k) n[k] = std::max(1, static_cast<int>(std::ceil(extent[k] / side - 1e-9)));
      const Eigen::Vector3d sub = extent.cwiseQuotient(n.cast<double>());
      const double radius = sub.norm() / 2;
      for (int i = 0; i < n.x(); ++i)
        for (int j = 0; j < n.y(); ++j)
          for (int k = 0; k < n.z(); ++k) {
            const Eigen::Vector3d centre =
                -extent / 2 + sub.cwiseProduct(Eigen::Vector3d(i + 0.5, j + 0.5, k + 0.5));
            spheres.emplace_back(centre, radius);
          }
      break;
    }
  }
  return spheres;
}

}  // namespace

RobotSpheres::RobotSpheres(const robot::RobotModel& robot) : robot_(robot) {
  const auto& links = robot.links();
  link_spheres_.resize(links.size());
  for (int l = 0; l < static_cast<int>(links.size()); ++l)
    for (const auto& shape : links[l].shapes)
      for (const auto& [centre, radius] : cover(shape)) {
        link_spheres_[l].push_back(static_cast<int>(spheres_.size()));
        spheres_.push_back({shape.link_from_shape * centre, radius, l});
      }
  // Flattened once, so the self-collision test is one loop over sphere pairs.
  for (const auto& [a, b] : robot.self_collision_pairs())
    for (int i : link_spheres_[a])
      for (int j : link_spheres_[b]) checked_pairs_.emplace_back(i, j);
}

void RobotSpheres::place(const robot::JointVector& q, double opening_m, const Eigen::Isometry3d& world_from_base,
                         std::vector<Sphere>& out) const {
  const auto link_poses = robot_.link_poses(q, opening_m);
  std::vector<Eigen::Isometry3d> world_from_link(link_poses.size());
  for (std::size_t l = 0; l < link_poses.size(); ++l) world_from_link[l] = world_from_base * link_poses[l];
  out.resize(spheres_.size());
  for (std::size_t i = 0; i < spheres_.size(); ++i) {
    out[i] = spheres_[i];
    out[i].centre = world_from_link[spheres_[i].link] * spheres_[i].centre;
  }
}

bool RobotSpheres::self_collision(const std::vector<Sphere>& placed, double margin_m) const {
  if (placed.size() != spheres_.size())
    throw Error("self_collision: " + std::to_string(placed.size()) + " spheres given, the robot has " +
                std::to_string(spheres_.size()) + " (place them first)");
  for (const auto& [i, j] : checked_pairs_) {
    const double reach = placed[i].radius_m + placed[j].radius_m - margin_m;
    if (reach > 0 && (placed[i].centre - placed[j].centre).squaredNorm() < reach * reach) return true;
  }
  return false;
}

}  // namespace qte::planning

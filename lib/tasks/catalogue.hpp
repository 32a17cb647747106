// Shared pieces of the task implementations (not part of the public task interface).
#pragma once

#include <Eigen/Core>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "tasks/task.hpp"

namespace qte::tasks {

struct NamedColour {
  std::string name;
  Eigen::Vector3f rgb;
};
const std::vector<NamedColour>& colours();

// `count` points uniform in the box [lo, hi], pairwise at least `min_distance_m` apart.
std::vector<Eigen::Vector3d> sample_separated(std::mt19937_64& rng, int count,
                                              const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
                                              double min_distance_m);
// As sample_separated, placing one point at a time (a layout too dense for drawing all at
// once); sample_separated stays as it is, since it decides the older tasks' scenes.
std::vector<Eigen::Vector3d> place_one_by_one(std::mt19937_64& rng, int count, const Eigen::Vector3d& lo,
                                              const Eigen::Vector3d& hi, double min_distance_m);
// A point uniform in the box [lo, hi] at least `min_distance_m` from each of `others`.
Eigen::Vector3d sample_away_from(std::mt19937_64& rng, const std::vector<Eigen::Vector3d>& others,
                                 const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, double min_distance_m);
// A number uniform in [lo, hi).
inline double uniform(std::mt19937_64& rng, double lo, double hi) {
  return std::uniform_real_distribution<double>(lo, hi)(rng);
}
// `count` distinct integers in [0, range), none equal to `excluded`.
std::vector<int> pick_distinct(std::mt19937_64& rng, int count, int range, int excluded);

// Where objects go on the table: x forward of the robot, y across (world frame, metres),
// heights relative to the table top.
constexpr double kRegionMinX = 0.0, kRegionMaxX = 0.3;
constexpr double kRegionMinY = -0.25, kRegionMaxY = 0.25;

}  // namespace qte::tasks

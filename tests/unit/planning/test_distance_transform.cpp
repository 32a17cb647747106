// The distance transform against brute force: every cell's squared distance to the nearest
// occupied cell, found by trying them all.
#include <gtest/gtest.h>

#include <limits>
#include <random>

#include "planning/distance_transform.hpp"

using qte::planning::squared_distance_transform;

namespace {

std::vector<float> brute_force(const std::vector<uint8_t>& occupied, const Eigen::Vector3i& size) {
  std::vector<Eigen::Vector3i> sites;
  for (int x = 0; x < size.x(); ++x)
    for (int y = 0; y < size.y(); ++y)
      for (int z = 0; z < size.z(); ++z)
        if (occupied[(x * size.y() + y) * size.z() + z]) sites.emplace_back(x, y, z);
  std::vector<float> d(occupied.size(), std::numeric_limits<float>::infinity());
  for (int x = 0; x < size.x(); ++x)
    for (int y = 0; y < size.y(); ++y)
      for (int z = 0; z < size.z(); ++z)
        for (const Eigen::Vector3i& s : sites)
          d[(x * size.y() + y) * size.z() + z] =
              std::min<float>(d[(x * size.y() + y) * size.z() + z], (s - Eigen::Vector3i(x, y, z)).squaredNorm());
  return d;
}

}  // namespace

TEST(DistanceTransform, MatchesBruteForceOnRandomGrids) {
  std::mt19937 rng(7);
  for (const Eigen::Vector3i& size : {Eigen::Vector3i(9, 7, 5), Eigen::Vector3i(1, 13, 4), Eigen::Vector3i(12, 1, 1),
                                     Eigen::Vector3i(6, 6, 17), Eigen::Vector3i(20, 11, 8)})
    for (double density : {0.002, 0.02, 0.3})
      for (int threads : {1, 2, 3}) {
        std::vector<uint8_t> occupied(size.prod());
        std::bernoulli_distribution hit(density);
        for (auto& o : occupied) o = hit(rng);
        EXPECT_EQ(squared_distance_transform(occupied, size, threads), brute_force(occupied, size))
            << size.transpose() << " density " << density << " threads " << threads;
      }
}

TEST(DistanceTransform, NothingOccupiedIsInfiniteEverywhere) {
  const Eigen::Vector3i size(4, 5, 6);
  for (float d : squared_distance_transform(std::vector<uint8_t>(size.prod(), 0), size))
    EXPECT_EQ(d, std::numeric_limits<float>::infinity());
}

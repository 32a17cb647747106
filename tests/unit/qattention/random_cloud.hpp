// Shared by the Q-attention tests: 2000 points spread uniformly over the default scene cube,
// all of one colour, drawn from `seed`.
#pragma once

#include <array>
#include <cstdint>
#include <random>
#include <vector>

#include "voxels/voxel_grid.hpp"

namespace qte::test_support {

struct RandomCloud {
  std::vector<float> xyz;
  std::vector<uint8_t> rgb;
  RandomCloud(uint32_t seed, std::array<uint8_t, 3> colour) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(0, 1);
    for (int i = 0; i < 2000; ++i) {
      xyz.insert(xyz.end(), {-0.3f + u(rng), -0.5f + u(rng), 0.6f + u(rng)});
      rgb.insert(rgb.end(), colour.begin(), colour.end());
    }
  }
  voxels::PointCloud view() const { return {xyz.data(), rgb.data(), rgb.size() / 3}; }
};

}  // namespace qte::test_support

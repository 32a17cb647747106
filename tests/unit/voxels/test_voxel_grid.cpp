#include <gtest/gtest.h>

#include <random>

#include "common/error.hpp"
#include "voxels/voxel_grid.hpp"

using namespace qte::voxels;

TEST(VoxelGrid, IndexAndCentreRoundTripAtEveryDepth) {
  CoarseToFine hierarchy;
  hierarchy.depths = 3;
  hierarchy.offsets_m = {0.15, 0.05};
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int trial = 0; trial < 1000; ++trial) {
    const Eigen::Vector3d target = hierarchy.scene.min_corner + Eigen::Vector3d(u(rng), u(rng), u(rng)) * hierarchy.scene.size_m;
    const auto indices = hierarchy.indices_of(target);
    ASSERT_EQ(indices.size(), 3u);
    Eigen::Vector3d centre;
    for (int d = 0; d < 3; ++d) {
      const GridBounds b = hierarchy.bounds_at(d, centre);
      ASSERT_TRUE(b.contains(indices[d]));
      centre = b.centre_of(indices[d]);
      // The centre's own index is the index, and the target lies within half a voxel of it.
      EXPECT_EQ(b.index_of(centre), indices[d]);
      EXPECT_LE((centre - target).cwiseAbs().maxCoeff(), b.voxel_size_m() / 2 + 1e-12) << "depth " << d;
    }
  }
}

TEST(VoxelGrid, DepthOneCoversThirtyCentimetresInTwoCentimetreVoxels) {
  CoarseToFine hierarchy;
  EXPECT_DOUBLE_EQ(hierarchy.scene.voxel_size_m(), 0.0625);
  const GridBounds deeper = hierarchy.bounds_at(1, {0.1, 0.2, 0.9});
  EXPECT_DOUBLE_EQ(deeper.size_m, 0.3);
  EXPECT_NEAR(deeper.voxel_size_m(), 0.01875, 1e-12);
  EXPECT_TRUE(deeper.centre_of({8, 8, 8}).isApprox(Eigen::Vector3d(0.1, 0.2, 0.9) + Eigen::Vector3d::Constant(0.01875 / 2)));
}

// One offset per depth below 0: with 0.15, 0.05 depth 1 is a 30 cm cube and depth 2 a 10 cm
// one (not another 30 cm cube), and the sub-hierarchy below depth 0 carries depth 2's offset.
TEST(VoxelGrid, EachDepthHasItsOwnOffset) {
  CoarseToFine h;
  h.depths = 3;
  h.offsets_m = CoarseToFine::parse_offsets("0.15,0.05", 3);
  const Eigen::Vector3d centre(0.1, 0.2, 0.9);
  EXPECT_DOUBLE_EQ(h.bounds_at(1, centre).size_m, 0.3);
  EXPECT_DOUBLE_EQ(h.bounds_at(2, centre).size_m, 0.1);
  EXPECT_NEAR(h.bounds_at(2, centre).voxel_size_m(), 0.00625, 1e-12);
  const CoarseToFine below = h.below(0, centre);
  EXPECT_EQ(below.depths, 2);
  EXPECT_DOUBLE_EQ(below.scene.size_m, 0.3);
  EXPECT_DOUBLE_EQ(below.bounds_at(1, centre).size_m, 0.1);
  EXPECT_NO_THROW(below.validate());
  // One offset for three depths, a negative one, words: refused.
  EXPECT_THROW(CoarseToFine::parse_offsets("0.15", 3), qte::Error);
  EXPECT_THROW(CoarseToFine::parse_offsets("0.15,-0.05", 3), qte::Error);
  EXPECT_THROW(CoarseToFine::parse_offsets("0.15,x", 3), qte::Error);
  EXPECT_EQ(CoarseToFine::parse_offsets("0.15", 2), std::vector<double>{0.15});
}

namespace {

// Reference: every voxel's channels computed by scanning all points for that voxel.
std::vector<float> brute_force(const std::vector<float>& xyz, const std::vector<uint8_t>& rgb, const GridBounds& b) {
  const int v = b.voxels;
  std::vector<float> out(static_cast<std::size_t>(v) * v * v * kChannels, 0.0f);
  for (int x = 0; x < v; ++x)
    for (int y = 0; y < v; ++y)
      for (int z = 0; z < v; ++z) {
        double sum[6] = {0, 0, 0, 0, 0, 0};
        int n = 0;
        for (std::size_t i = 0; i < rgb.size() / 3; ++i) {
          const Eigen::Vector3d p(xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]);
          if (!p.allFinite()) continue;
          const Eigen::Vector3d lo = b.min_corner + Eigen::Vector3d(x, y, z) * b.voxel_size_m();
          if ((p.array() < lo.array()).any() || (p.array() >= (lo.array() + b.voxel_size_m())).any()) continue;
          for (int k = 0; k < 3; ++k) sum[k] += p[k], sum[3 + k] += rgb[3 * i + k];
          ++n;
        }
        float* o = out.data() + ((x * v + y) * v + z) * kChannels;
        if (n > 0) {
          for (int k = 0; k < 3; ++k) o[k] = static_cast<float>(sum[k] / n);
          for (int k = 0; k < 3; ++k) o[3 + k] = static_cast<float>(sum[3 + k] / n / 255.0 * 2 - 1);
          o[9] = 1;
        }
        o[6] = static_cast<float>(x) / v;
        o[7] = static_cast<float>(y) / v;
        o[8] = static_cast<float>(z) / v;
      }
  return out;
}

void random_cloud(std::mt19937& rng, std::size_t n, std::vector<float>& xyz, std::vector<uint8_t>& rgb) {
  std::uniform_real_distribution<float> u(-0.5f, 1.7f);  // much of it outside the bounds
  xyz.resize(3 * n);
  rgb.resize(3 * n);
  for (auto& c : xyz) c = u(rng);
  for (auto& c : rgb) c = static_cast<uint8_t>(rng() % 256);
  for (std::size_t i = 0; i < n; i += 17) xyz[3 * i + 1] = NAN;  // pixels without a return
}

}  // namespace

TEST(Voxelize, EqualsBruteForceOnRandomCloudsInAllTenChannels) {
  std::mt19937 rng(3);
  for (int trial = 0; trial < 3; ++trial) {
    std::vector<float> xyz;
    std::vector<uint8_t> rgb;
    random_cloud(rng, 3000, xyz, rgb);
    GridBounds b;
    b.voxels = 8;
    b.min_corner = Eigen::Vector3d(0.0, 0.1, 0.2);
    b.size_m = 0.9;
    std::vector<float> grid(8 * 8 * 8 * kChannels);
    voxelize({xyz.data(), rgb.data(), rgb.size() / 3}, b, grid.data());
    const auto expected = brute_force(xyz, rgb, b);
    int occupied = 0;
    for (std::size_t i = 0; i < grid.size(); ++i) {
      ASSERT_NEAR(grid[i], expected[i], 2e-5) << "value " << i << " channel " << i % kChannels;
      occupied += (i % kChannels == 9) && grid[i] > 0;
    }
    EXPECT_GT(occupied, 100);
  }
}

TEST(Voxelize, PointsOutsideTheBoundsAndNaNsAreIgnored) {
  GridBounds b;
  b.voxels = 4;
  b.min_corner = Eigen::Vector3d::Zero();
  b.size_m = 1.0;
  const std::vector<float> xyz = {1.0f, 0.5f, 0.5f, -0.001f, 0.5f, 0.5f, NAN, 0.5f, 0.5f, 0.5f, 0.5f, 0.5f};
  const std::vector<uint8_t> rgb = {255, 255, 255, 255, 255, 255, 255, 255, 255, 0, 0, 0};
  std::vector<float> grid(4 * 4 * 4 * kChannels);
  voxelize({xyz.data(), rgb.data(), 4}, b, grid.data());
  float occupied = 0;
  for (std::size_t i = 9; i < grid.size(); i += kChannels) occupied += grid[i];
  EXPECT_EQ(occupied, 1.0f);  // only (0.5, 0.5, 0.5), in voxel (2, 2, 2), black
  const float* voxel = grid.data() + ((2 * 4 + 2) * 4 + 2) * kChannels;
  EXPECT_EQ(voxel[9], 1.0f);
  EXPECT_EQ(voxel[3], -1.0f);
}

TEST(Voxelize, ManyGridsInOnePassEqualOneAtATime) {
  std::mt19937 rng(4);
  std::vector<float> xyz;
  std::vector<uint8_t> rgb;
  random_cloud(rng, 5000, xyz, rgb);
  std::vector<GridBounds> grids;
  for (int k = 0; k < 5; ++k) grids.push_back(GridBounds::around({0.1 * k, 0.2, 0.3 + 0.1 * k}, 0.15, 16));
  const std::size_t per = 16 * 16 * 16 * kChannels;
  std::vector<float> many(per * grids.size()), one(per);
  voxelize_many({xyz.data(), rgb.data(), rgb.size() / 3}, grids, many.data());
  for (std::size_t k = 0; k < grids.size(); ++k) {
    voxelize({xyz.data(), rgb.data(), rgb.size() / 3}, grids[k], one.data());
    EXPECT_TRUE(std::equal(one.begin(), one.end(), many.begin() + k * per)) << k;
  }
}

// Tree expansion: K = 1 is the greedy coarse-to-fine choice; K > 1 lets a finer depth overturn
// a coarse choice; branches are evaluated in one batched call per depth.
#include <gtest/gtest.h>

#include <random>

#include "qattention/tree_expansion.hpp"

using namespace qte;
using namespace qte::qattention;

namespace {

constexpr int V = 16, kCells = V * V * V;

struct Cloud {
  std::vector<float> xyz;
  std::vector<uint8_t> rgb;
  Cloud() {
    std::mt19937 rng(1);
    std::uniform_real_distribution<float> u(0, 1);
    for (int i = 0; i < 2000; ++i) {
      xyz.insert(xyz.end(), {-0.3f + u(rng), -0.5f + u(rng), 0.6f + u(rng)});
      rgb.insert(rgb.end(), {120, 80, 40});
    }
  }
  voxels::PointCloud view() const { return {xyz.data(), rgb.data(), rgb.size() / 3}; }
};

int flat(int x, int y, int z) { return (x * V + y) * V + z; }

// A stand-in for the networks (this is a test of the expansion, not of them): depth 0 likes
// voxel A best and B second; below A the best Q is 0.1, below B it is 0.9.
struct ScriptedQ {
  int calls[2] = {0, 0};
  int last_batch[2] = {0, 0};
  nets::QValues operator()(int depth, const float*, const float*, int batch) {
    calls[depth] += 1;
    last_batch[depth] = batch;
    nets::QValues out;
    out.batch = batch;
    out.translation.assign(static_cast<std::size_t>(batch) * kCells, 0.0f);
    if (depth == 0) {
      out.translation[flat(3, 4, 5)] = 1.0f;   // A
      out.translation[flat(10, 2, 7)] = 0.9f;  // B
      out.translation[flat(1, 1, 1)] = 0.5f;
    } else {
      for (int i = 0; i < batch; ++i) {
        const float best = i == 0 ? 0.1f : (i == 1 ? 0.9f : 0.2f);  // branches in top-k order
        out.translation[static_cast<std::size_t>(i) * kCells + flat(8, 8, 8 + i % 8)] = best;
      }
      out.rotation.assign(static_cast<std::size_t>(batch) * 3 * 72, 0.0f);
      out.gripper.assign(static_cast<std::size_t>(batch) * 2, 0.0f);
      for (int i = 0; i < batch; ++i) {
        out.rotation[static_cast<std::size_t>(i) * 216 + 10 + i] = 1;  // axis 0 bin 10 + i
        out.gripper[static_cast<std::size_t>(i) * 2 + (i == 1 ? 1 : 0)] = 1;
      }
    }
    return out;
  }
};

}  // namespace

TEST(TopK, BestFirstTiesToTheLowerIndex) {
  const float q[6] = {0.5f, 2.0f, 0.5f, -1.0f, 2.0f, 1.0f};
  EXPECT_EQ(top_k(q, 6, 3), (std::vector<int>{1, 4, 5}));
  EXPECT_EQ(top_k(q, 6, 10).size(), 6u);
}

TEST(TreeExpansion, KOneIsTheGreedyCoarseToFineChoice) {
  const Cloud cloud;
  ScriptedQ q;
  voxels::CoarseToFine hierarchy;
  const Choice c = expand(std::ref(q), hierarchy, cloud.view(), {1, 0, 0, 0}, 1);
  EXPECT_EQ(c.indices[0], Eigen::Vector3i(3, 4, 5));  // A, the depth-0 argmax
  EXPECT_EQ(c.indices[1], Eigen::Vector3i(8, 8, 8));  // the depth-1 argmax below it
  EXPECT_EQ(c.expanded_grids, 2);
  EXPECT_FLOAT_EQ(c.value, (1.0f + 0.1f) / 2);
  // Depth 1 is centred on A's voxel centre.
  const Eigen::Vector3d a = hierarchy.scene.centre_of({3, 4, 5});
  EXPECT_TRUE((c.bounds[1].min_corner + Eigen::Vector3d::Constant(0.15)).isApprox(a));
  EXPECT_EQ(c.rotation_bins[0], 10);
  EXPECT_FALSE(c.gripper_open);
}

TEST(TreeExpansion, AFinerDepthOverturnsTheCoarseChoiceInOneBatchedCall) {
  const Cloud cloud;
  ScriptedQ q;
  const Choice c = expand(std::ref(q), voxels::CoarseToFine{}, cloud.view(), {1, 0, 0, 0}, 10);
  EXPECT_EQ(c.indices[0], Eigen::Vector3i(10, 2, 7));  // B: (0.9 + 0.9) / 2 beats (1 + 0.1) / 2
  EXPECT_EQ(c.indices[1], Eigen::Vector3i(8, 8, 9));
  EXPECT_FLOAT_EQ(c.value, 0.9f);
  EXPECT_EQ(q.calls[0], 1);
  EXPECT_EQ(q.calls[1], 1);  // all ten branches in one call
  EXPECT_EQ(q.last_batch[1], 10);
  EXPECT_EQ(c.expanded_grids, 11);
  EXPECT_EQ(c.rotation_bins[0], 11);  // from the chosen branch's own outputs
  EXPECT_TRUE(c.gripper_open);
}

TEST(TreeExpansion, RealNetworksGreedyEqualsManualArgmax) {
  const Cloud cloud;
  nets::seed_torch(3);
  nets::NetConfig config;
  const auto networks = nets::make_coarse_to_fine_nets(config, 2);
  voxels::CoarseToFine hierarchy;
  const std::vector<float> proprio = {1, 0.04f, 0.04f, -1};
  const Choice c = expand(network_evaluator(networks), hierarchy, cloud.view(), proprio, 1);
  // By hand: voxelize, predict, argmax; again one depth down.
  std::vector<float> grid(kCells * voxels::kChannels);
  voxels::voxelize(cloud.view(), hierarchy.scene, grid.data());
  const auto q0 = networks[0].predict(grid.data(), proprio.data(), 1);
  const int a0 = top_k(q0.translation.data(), kCells, 1)[0];
  EXPECT_EQ(c.indices[0], Eigen::Vector3i(a0 / (V * V), (a0 / V) % V, a0 % V));
  const voxels::GridBounds b1 = hierarchy.bounds_at(1, hierarchy.scene.centre_of(c.indices[0]));
  voxels::voxelize(cloud.view(), b1, grid.data());
  const auto q1 = networks[1].predict(grid.data(), proprio.data(), 1);
  const int a1 = top_k(q1.translation.data(), kCells, 1)[0];
  EXPECT_EQ(c.indices[1], Eigen::Vector3i(a1 / (V * V), (a1 / V) % V, a1 % V));
  for (int axis = 0; axis < 3; ++axis) {
    EXPECT_GE(c.rotation_bins[axis], 0);
    EXPECT_LT(c.rotation_bins[axis], 72);
  }
  // K = 5 evaluates 1 + 5 grids and its value is at least the greedy one's.
  const Choice wide = expand(network_evaluator(networks), hierarchy, cloud.view(), proprio, 5);
  EXPECT_EQ(wide.expanded_grids, 6);
  EXPECT_GE(wide.value, c.value - 1e-6f);
}

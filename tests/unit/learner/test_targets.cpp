// The bootstrap targets against a brute-force reference written here: Algorithm 2 as a plain
// recursion, one grid at a time, with the online Q function choosing (the top-K voxels of
// every non-leaf grid, the leaf voxel, the heads' bins) and the target Q function valuing what
// it chose (branch values and the max over branches on the target values). The two Q
// functions disagree, so a target that lets the target network rank, or the online network
// value, gives other numbers.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "learner/targets.hpp"
#include "../qattention/content_q.hpp"
#include "../qattention/random_cloud.hpp"

using namespace qte;
using namespace qte::qattention;

namespace {

constexpr int V = 16, kCells = V * V * V;

int first_best(const float* q, int count) { return static_cast<int>(std::max_element(q, q + count) - q); }

std::vector<int> k_best(const float* q, int k) {
  std::vector<int> order(kCells);
  for (int i = 0; i < kCells; ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return q[a] > q[b]; });
  order.resize(k);
  return order;
}

Eigen::Vector3i voxel_of(int flat) { return {flat / (V * V), (flat / V) % V, flat % V}; }

// What the reference returns for one subtree: its value, and along its best path the value of
// the subtree at each depth (the per-depth bootstrap values), the target Q of each chosen
// voxel, and the heads' target values at the online network's bins.
struct Subtree {
  float value = 0;
  std::vector<float> depth_values, q_values;
  float rotation[3] = {0, 0, 0}, gripper = 0;
};

Subtree reference(const DepthEvaluator& online, const DepthEvaluator& target, const voxels::CoarseToFine& h,
                  const voxels::PointCloud& cloud, const std::vector<float>& proprio, int k, int depth,
                  const voxels::GridBounds& bounds) {
  std::vector<float> grid(static_cast<std::size_t>(kCells) * voxels::kChannels);
  voxels::voxelize(cloud, bounds, grid.data());
  const nets::QValues on = online(depth, grid.data(), proprio.data(), 1);
  const nets::QValues tg = target(depth, grid.data(), proprio.data(), 1);
  Subtree best;
  if (depth + 1 == h.depths) {
    const int a = first_best(on.translation.data(), kCells);
    best.value = tg.translation[a];
    best.depth_values = best.q_values = {tg.translation[a]};
    for (int axis = 0; axis < 3; ++axis)
      best.rotation[axis] = tg.rotation[axis * 72 + first_best(on.rotation.data() + axis * 72, 72)];
    best.gripper = tg.gripper[first_best(on.gripper.data(), 2)];
    return best;
  }
  best.value = -std::numeric_limits<float>::infinity();
  for (int voxel : k_best(on.translation.data(), k)) {
    Subtree below = reference(online, target, h, cloud, proprio, k, depth + 1,
                              h.bounds_at(depth + 1, bounds.centre_of(voxel_of(voxel))));
    const float value = (tg.translation[voxel] + below.value) / 2;
    if (value > best.value) {
      best = below;
      best.value = value;
      best.depth_values.insert(best.depth_values.begin(), value);
      best.q_values.insert(best.q_values.begin(), tg.translation[voxel]);
    }
  }
  return best;
}

struct Case {
  learner::LearnerConfig config;
  std::vector<test_support::RandomCloud> clouds;
  learner::Minibatch batch;
  Case(int depths, int tree_k) {
    config.hierarchy.depths = depths;
    config.hierarchy.offsets_m = depths == 3 ? std::vector<double>{0.15, 0.05} : std::vector<double>{0.15};
    config.tree_target_k = tree_k;
    for (uint32_t seed : {11u, 12u, 13u}) clouds.emplace_back(seed, std::array<uint8_t, 3>{200, 100, 50});
    batch.size = 3;
    for (int i = 0; i < 3; ++i) {
      batch.next_clouds.push_back(std::make_shared<voxels::ObservationCloud>(voxels::ObservationCloud{clouds[i].xyz, clouds[i].rgb}));
      batch.next_proprio.push_back({1, 0.04f, 0.04f, 0.1f * i});
    }
    batch.reward = {0, 0, 100};        // the last one reaches the goal: r * 0.01 = 1 ...
    batch.discount = {0.99f, 0.5f, 0};  // ... and is terminal
  }
};

float bootstrap(const learner::Minibatch& b, int i, float value) {
  return std::max(0.0f, b.reward[i] * 0.01f + b.discount[i] * value);
}

}  // namespace

// Tree-expanded targets, K = 1 and 3 over 2 depths and K = 3 over 3 depths: indices from the
// online network, values from the target network, at every depth and in the heads.
TEST(BootstrapTargets, TreeExpansionRanksWithTheOnlineNetworkAndValuesWithTheTarget) {
  const DepthEvaluator online = test_support::content_q(0.0f), target = test_support::content_q(1.3f);
  for (auto [depths, k] : {std::pair{2, 1}, std::pair{2, 3}, std::pair{3, 3}}) {
    SCOPED_TRACE("depths " + std::to_string(depths) + ", K " + std::to_string(k));
    Case c(depths, k);
    const learner::Targets t = learner::bootstrap_targets(online, target, c.config, c.batch);
    bool other_than_target_ranking = false;
    for (int i = 0; i < c.batch.size; ++i) {
      const Subtree want = reference(online, target, c.config.hierarchy, c.batch.next_clouds[i]->view(),
                                     c.batch.next_proprio[i], k, 0, c.config.hierarchy.scene);
      ASSERT_EQ(want.depth_values.size(), static_cast<std::size_t>(depths));
      for (int d = 0; d < depths; ++d)
        EXPECT_FLOAT_EQ(t.translation[d][i], bootstrap(c.batch, i, want.depth_values[d])) << "sample " << i << " depth " << d;
      for (int axis = 0; axis < 3; ++axis)
        EXPECT_FLOAT_EQ(t.rotation[3 * i + axis], bootstrap(c.batch, i, want.rotation[axis]));
      EXPECT_FLOAT_EQ(t.gripper[i], bootstrap(c.batch, i, want.gripper));
      // The target network ranking and valuing alone (the earlier, overestimating target).
      const Subtree self = reference(target, target, c.config.hierarchy, c.batch.next_clouds[i]->view(),
                                     c.batch.next_proprio[i], k, 0, c.config.hierarchy.scene);
      if (std::abs(self.value - want.value) > 1e-4f) other_than_target_ranking = true;
    }
    EXPECT_TRUE(other_than_target_ranking) << "the case cannot tell who ranks";
  }
}

// K = 0 (C2F-ARM): down the online network's greedy path, each depth's own target Q, no averaging.
TEST(BootstrapTargets, DoubleDqnValuesEachDepthsGreedyVoxelWithTheTargetNetwork) {
  const DepthEvaluator online = test_support::content_q(0.0f), target = test_support::content_q(1.3f);
  Case c(2, 0);
  const learner::Targets t = learner::bootstrap_targets(online, target, c.config, c.batch);
  for (int i = 0; i < c.batch.size; ++i) {
    const Subtree greedy = reference(online, target, c.config.hierarchy, c.batch.next_clouds[i]->view(),
                                     c.batch.next_proprio[i], 1, 0, c.config.hierarchy.scene);
    for (int d = 0; d < 2; ++d) EXPECT_FLOAT_EQ(t.translation[d][i], bootstrap(c.batch, i, greedy.q_values[d]));
    EXPECT_FLOAT_EQ(t.gripper[i], bootstrap(c.batch, i, greedy.gripper));
  }
}

// --tree-target 1 with one network is the paper's Algorithm 2 with K = 1: the value at depth 0
// is (q0 + q1) / 2 of the greedy path.
TEST(BootstrapTargets, TreeTargetOneIsAlgorithmTwoWithKOne) {
  const DepthEvaluator q = test_support::content_q(0.4f);
  Case c(2, 1);
  const learner::Targets t = learner::bootstrap_targets(q, q, c.config, c.batch);
  std::vector<voxels::PointCloud> clouds;
  for (const auto& cloud : c.batch.next_clouds) clouds.push_back(cloud->view());
  const auto algorithm2 = expand_batch(q, c.config.hierarchy, clouds, c.batch.next_proprio, 1);
  for (int i = 0; i < c.batch.size; ++i) {
    EXPECT_FLOAT_EQ(t.translation[0][i], bootstrap(c.batch, i, algorithm2[i].value));
    EXPECT_FLOAT_EQ(t.translation[1][i], bootstrap(c.batch, i, algorithm2[i].q_values[1]));
  }
  EXPECT_FLOAT_EQ(t.translation[0][2], 1.0f);  // terminal: the scaled reward alone
}

// An adaptive tree target (--tree-target auto): with a margin no volume exceeds it is the
// fixed-K target, and it reports K branches; with margin 0 it is the K = 1 tree (one branch).
TEST(BootstrapTargets, AdaptiveTreeTargetBetweenKOneAndKMax) {
  const DepthEvaluator online = test_support::content_q(0.0f), target = test_support::content_q(1.3f);
  Case fixed(2, 3), open(2, 3), k1(2, 1), closed(2, 3);
  open.config.tree_branching = Branching::within_margin(std::numeric_limits<float>::infinity(), 3);
  closed.config.tree_branching = Branching::within_margin(0.0f, 3);
  const learner::Targets want = learner::bootstrap_targets(online, target, fixed.config, fixed.batch);
  const learner::Targets got = learner::bootstrap_targets(online, target, open.config, open.batch);
  EXPECT_EQ(got.translation, want.translation);
  EXPECT_EQ(got.rotation, want.rotation);
  EXPECT_EQ(got.mean_branches, std::vector<double>{3.0});
  EXPECT_EQ(want.mean_branches, std::vector<double>{3.0});
  const learner::Targets one = learner::bootstrap_targets(online, target, k1.config, k1.batch);
  const learner::Targets zero = learner::bootstrap_targets(online, target, closed.config, closed.batch);
  EXPECT_EQ(zero.translation, one.translation);
  EXPECT_EQ(zero.mean_branches, std::vector<double>{1.0});
  // K = 0 (double DQN) has no tree to report.
  Case none(2, 0);
  EXPECT_TRUE(learner::bootstrap_targets(online, target, none.config, none.batch).mean_branches.empty());
}

// Each next state is evaluated once: samples that reach the same state (the same next_state id)
// share its trees, a sample whose chain ended (discount 0) needs none, and the targets are
// those of every sample evaluated on its own.
TEST(BootstrapTargets, EachNextStateIsEvaluatedOnce) {
  int online_grids = 0, target_grids = 0;
  const DepthEvaluator plain_online = test_support::content_q(0.0f), plain_target = test_support::content_q(1.3f);
  const DepthEvaluator online = [&](int depth, const float* g, const float* p, int batch) {
    online_grids += batch;
    return plain_online(depth, g, p, batch);
  };
  const DepthEvaluator target = [&](int depth, const float* g, const float* p, int batch) {
    target_grids += batch;
    return plain_target(depth, g, p, batch);
  };
  Case c(2, 3);
  // Four samples: 0 and 3 reach the same state with other rewards and discounts, 1 its own, 2 ends.
  c.batch.size = 4;
  c.batch.next_clouds.push_back(c.batch.next_clouds[0]);
  c.batch.next_proprio.push_back(c.batch.next_proprio[0]);
  c.batch.reward = {0, 0, 100, 30};
  c.batch.discount = {0.99f, 0.5f, 0, 0.9f};
  c.batch.next_state = {7, 8, 9, 7};
  const learner::Targets shared = learner::bootstrap_targets(online, target, c.config, c.batch);
  EXPECT_EQ(learner::next_states_evaluated(c.batch), 2);
  EXPECT_EQ(online_grids, 2 * (1 + 3));  // two states, each a root and 3 branches
  EXPECT_EQ(target_grids, 2 * (1 + 3));

  learner::Minibatch apart = c.batch;  // every sample its own state, none skipped
  apart.next_state.clear();
  apart.discount[2] = 0.25f;
  const learner::Targets alone = learner::bootstrap_targets(plain_online, plain_target, c.config, apart);
  for (int i : {0, 1, 3})
    for (int d = 0; d < 2; ++d) EXPECT_FLOAT_EQ(shared.translation[d][i], alone.translation[d][i]) << i;
  EXPECT_FLOAT_EQ(shared.translation[0][3], 0.3f + 0.9f * (alone.translation[0][0] / 0.99f));
  for (int d = 0; d < 2; ++d) EXPECT_FLOAT_EQ(shared.translation[d][2], 1.0f);  // the scaled reward alone
  EXPECT_EQ(shared.mean_branches, std::vector<double>{3.0});
}

// Tree expansion: K = 1 is the greedy coarse-to-fine choice; K > 1 lets a finer depth overturn
// a coarse choice; branches are evaluated in one batched call per depth, and the batched
// expansion chooses what the paper's Algorithm 2, run one branch at a time, chooses.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <random>
#include <set>

#include "common/error.hpp"
#include "qattention/tree_expansion.hpp"
#include "content_q.hpp"
#include "random_cloud.hpp"

using namespace qte;
using namespace qte::qattention;

namespace {

constexpr int V = 16, kCells = V * V * V;

struct Cloud : test_support::RandomCloud {
  Cloud() : RandomCloud(1, {120, 80, 40}) {}
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
  // Nothing overruled: the recorded depth-0 argmax is the voxel taken; none for the leaf.
  ASSERT_EQ(c.argmax_indices.size(), 1u);
  EXPECT_EQ(c.argmax_indices[0], c.indices[0]);
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
  // What the action records of it: depth 0's argmax was A, which depth 1 overruled.
  ASSERT_EQ(c.argmax_indices.size(), 1u);
  EXPECT_EQ(c.argmax_indices[0], Eigen::Vector3i(3, 4, 5));
  EXPECT_NE(c.argmax_indices[0], c.indices[0]);
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

namespace {

// ---- The paper's Algorithm 2 written plainly: a recursion with one forward per branch ----

Eigen::Vector3i voxel_of(int flat_index) { return {flat_index / (V * V), (flat_index / V) % V, flat_index % V}; }

int first_best(const float* q, int count) { return static_cast<int>(std::max_element(q, q + count) - q); }

// The k best voxels, best first, equal Q in index order (as top_k, written independently).
std::vector<int> k_best(const float* q, int k) {
  std::vector<int> order(kCells);
  for (int i = 0; i < kCells; ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return q[a] > q[b]; });
  order.resize(std::min(k, kCells));
  return order;
}

struct Path {
  float value = 0;
  std::vector<Eigen::Vector3i> indices;
  std::vector<float> q_values;
  Eigen::Vector3i rotation_bins = Eigen::Vector3i::Zero();
  bool gripper_open = true;
};

// QTE(depth, obs, centre): voxelize the grid; at the last depth return its max Q; otherwise
// recurse below each of the top-K voxels and return the best (q_k + q'_k) / 2.
Path algorithm2(const DepthEvaluator& evaluate, const voxels::CoarseToFine& hierarchy, const voxels::PointCloud& cloud,
                const std::vector<float>& proprio, int k, int depth, const voxels::GridBounds& bounds, int& calls) {
  std::vector<float> grid(static_cast<std::size_t>(kCells) * voxels::kChannels);
  voxels::voxelize(cloud, bounds, grid.data());
  const nets::QValues out = evaluate(depth, grid.data(), proprio.data(), 1);
  calls += 1;
  const float* q = out.translation.data();
  Path best;
  if (depth + 1 == hierarchy.depths) {
    const int a = first_best(q, kCells);
    best.value = q[a];
    best.indices = {voxel_of(a)};
    best.q_values = {q[a]};
    if (!out.rotation.empty()) {
      for (int axis = 0; axis < 3; ++axis) best.rotation_bins[axis] = first_best(out.rotation.data() + axis * 72, 72);
      best.gripper_open = out.gripper[1] > out.gripper[0];
    }
    return best;
  }
  best.value = -std::numeric_limits<float>::infinity();
  for (int voxel : k_best(q, k)) {
    Path below = algorithm2(evaluate, hierarchy, cloud, proprio, k, depth + 1,
                            hierarchy.bounds_at(depth + 1, bounds.centre_of(voxel_of(voxel))), calls);
    const float value = (q[voxel] + below.value) / 2;
    if (value > best.value) {  // the first of equal values, as max() over the list
      best = below;
      best.value = value;
      best.indices.insert(best.indices.begin(), voxel_of(voxel));
      best.q_values.insert(best.q_values.begin(), q[voxel]);
    }
  }
  return best;
}

// Batched expand and the plain recursion side by side; `exact`: the same floats (a Q function
// of the grid alone), otherwise equal up to the rounding of batched against single forwards.
// The recursion evaluates with `reference` (every output of every grid at once).
void expect_same_as_algorithm2(const DepthEvaluator& evaluate, const DepthEvaluator& reference, int depths, int k,
                               const voxels::PointCloud& cloud, bool exact) {
  SCOPED_TRACE("depths " + std::to_string(depths) + ", K " + std::to_string(k));
  voxels::CoarseToFine hierarchy;
  hierarchy.depths = depths;
  hierarchy.offsets_m.assign(std::max(depths - 1, 1), 0.15);
  const std::vector<float> proprio = {1, 0.04f, 0.04f, 0.5f};
  int batched_calls = 0, plain_calls = 0;
  const DepthEvaluator counted = [&](int depth, const float* grids, const float* p, int batch) {
    batched_calls += 1;
    return evaluate(depth, grids, p, batch);
  };
  const Choice c = expand(counted, hierarchy, cloud, proprio, k);
  const Path p = algorithm2(reference, hierarchy, cloud, proprio, k, 0, hierarchy.scene, plain_calls);
  int grids = 0;
  for (int d = 0, width = 1; d < depths; ++d, width *= k) grids += width;  // 1 + K + K^2 + ...
  EXPECT_EQ(batched_calls, depths);  // one batched forward per depth
  EXPECT_EQ(plain_calls, grids);     // one forward per branch
  EXPECT_EQ(c.expanded_grids, grids);
  ASSERT_EQ(c.indices.size(), static_cast<std::size_t>(depths));
  for (int d = 0; d < depths; ++d) {
    EXPECT_EQ(c.indices[d], p.indices[d]) << "depth " << d;
    if (exact)
      EXPECT_EQ(c.q_values[d], p.q_values[d]) << "depth " << d;
    else
      EXPECT_NEAR(c.q_values[d], p.q_values[d], 1e-5) << "depth " << d;
  }
  if (exact)
    EXPECT_EQ(c.value, p.value);
  else
    EXPECT_NEAR(c.value, p.value, 1e-5);
  EXPECT_EQ(c.rotation_bins, p.rotation_bins);
  EXPECT_EQ(c.gripper_open, p.gripper_open);
}

void expect_same_as_algorithm2(const DepthEvaluator& evaluate, int depths, int k, const voxels::PointCloud& cloud,
                               bool exact) {
  expect_same_as_algorithm2(evaluate, evaluate, depths, k, cloud, exact);
}

// Points of a small object: a 3 x 3 x 3 lattice, 8 mm apart, around `centre`.
void add_object(const Eigen::Vector3d& centre, std::array<uint8_t, 3> colour, std::vector<float>& xyz,
                std::vector<uint8_t>& rgb) {
  for (int i = -1; i <= 1; ++i)
    for (int j = -1; j <= 1; ++j)
      for (int l = -1; l <= 1; ++l) {
        const Eigen::Vector3d p = centre + 0.008 * Eigen::Vector3d(i, j, l);
        xyz.insert(xyz.end(), {static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z())});
        rgb.insert(rgb.end(), colour.begin(), colour.end());
      }
}

}  // namespace

// Coarse ambiguity, the case QTE is for: two yellow shapes the coarse grid cannot tell apart
// (one voxel each, the same colour to its Q function; the distractor, 1 cm taller, scores a
// little higher), the fine grid can (it sees the target's shade).
TEST(TreeExpansion, FinerDepthResolvesCoarseAmbiguityBetweenTwoObjects) {
  const voxels::CoarseToFine hierarchy;
  const Eigen::Vector3d target = hierarchy.scene.centre_of({4, 8, 4});
  const Eigen::Vector3d distractor = hierarchy.scene.centre_of({11, 4, 4}) + Eigen::Vector3d(0, 0, 0.01);
  std::vector<float> xyz;
  std::vector<uint8_t> rgb;
  add_object(target, {250, 210, 0}, xyz, rgb);
  add_object(distractor, {250, 210, 60}, xyz, rgb);
  const voxels::PointCloud cloud{xyz.data(), rgb.data(), rgb.size() / 3};

  const DepthEvaluator q = [](int depth, const float* grids, const float*, int batch) {
    nets::QValues out;
    out.batch = batch;
    out.translation.assign(static_cast<std::size_t>(batch) * kCells, depth == 0 ? 0.0f : -1.0f);
    for (int b = 0; b < batch; ++b)
      for (int cell = 0; cell < kCells; ++cell) {
        const float* c = grids + (static_cast<std::size_t>(b) * kCells + cell) * voxels::kChannels;
        if (c[9] == 0) continue;  // empty
        float& value = out.translation[static_cast<std::size_t>(b) * kCells + cell];
        if (depth == 0)
          value = 0.5f + 0.1f * (c[2] - 0.6f);  // any yellow thing; taller is a little better
        else
          value = c[5] < -0.9f ? 1.0f : 0.0f;   // the target's shade (no blue) only
      }
    return out;
  };
  const Choice greedy = expand(q, hierarchy, cloud, {1, 0.04f, 0.04f, 1}, 1);
  EXPECT_EQ(greedy.indices[0], Eigen::Vector3i(11, 4, 4));  // the distractor, by its coarse Q
  EXPECT_LT((greedy.position() - distractor).norm(), 0.03);
  EXPECT_NEAR(greedy.value, (greedy.q_values[0] + 0.0f) / 2, 1e-7);
  for (int k : {2, 5, 10}) {
    SCOPED_TRACE("K " + std::to_string(k));
    const Choice c = expand(q, hierarchy, cloud, {1, 0.04f, 0.04f, 1}, k);
    EXPECT_EQ(c.indices[0], Eigen::Vector3i(4, 8, 4));  // the target, by what depth 1 sees
    EXPECT_LT((c.position() - target).norm(), 0.02);
    EXPECT_LT(c.q_values[0], greedy.q_values[0]);       // though its coarse Q is lower
    EXPECT_FLOAT_EQ(c.q_values[1], 1.0f);
    EXPECT_FLOAT_EQ(c.value, (c.q_values[0] + 1.0f) / 2);
  }
}

// Three depths by hand. Four points, labelled by their red value, in two groups (green) that
// fall in one depth-0 voxel each; deeper grids hold each point in a voxel of its own. Empty
// voxels have Q -1. Q by depth and label:
//   depth 0: group A 0.625, group B 0.5625
//   depth 1: a1 0.25, a2 0.5, b1 0.875, b2 0.125
//   depth 2: a1 0.75, a2 0,   b1 0,     b2 0.625
// A depth-2 grid (centre +- 0.15 m) holds both points of its group, so a leaf below group A is
// worth 0.75 and one below group B 0.625. Below A: a2 (0.5 + 0.75) / 2 = 0.625 beats a1 0.5;
// below B: b1 (0.875 + 0.625) / 2 = 0.75. Root: A (0.625 + 0.625) / 2 = 0.625 against B
// (0.5625 + 0.75) / 2 = 0.65625: K = 2 goes B, b1, b2. Greedy goes A, a2, a1: 0.625.
TEST(TreeExpansion, ThreeDepthsNestAsAlgorithmTwoByHand) {
  voxels::CoarseToFine hierarchy;
  hierarchy.depths = 3;
  hierarchy.offsets_m = {0.15, 0.15};  // depth 2 as wide as depth 1: the groups' geometry below
  const Eigen::Vector3d group_a = hierarchy.scene.centre_of({4, 8, 4});
  const Eigen::Vector3d group_b = hierarchy.scene.centre_of({11, 4, 4});
  const Eigen::Vector3d along_x(0.02, 0, 0), along_y(0, 0.02, 0);
  const std::array<Eigen::Vector3d, 4> points = {group_a - along_x, group_a + along_x,   // a1, a2
                                                 group_b - along_y, group_b + along_y};  // b1, b2
  std::vector<float> xyz;
  std::vector<uint8_t> rgb;
  for (int label = 0; label < 4; ++label) {
    const Eigen::Vector3f p = points[label].cast<float>();
    xyz.insert(xyz.end(), {p.x(), p.y(), p.z()});
    rgb.insert(rgb.end(), {static_cast<uint8_t>(64 * label), static_cast<uint8_t>(label < 2 ? 0 : 255), 0});
  }
  const voxels::PointCloud cloud{xyz.data(), rgb.data(), rgb.size() / 3};
  const float by_group[2] = {0.625f, 0.5625f};
  const float by_label[3][4] = {{0, 0, 0, 0}, {0.25f, 0.5f, 0.875f, 0.125f}, {0.75f, 0.0f, 0.0f, 0.625f}};
  const DepthEvaluator q = [&](int depth, const float* grids, const float*, int batch) {
    nets::QValues out;
    out.batch = batch;
    out.translation.assign(static_cast<std::size_t>(batch) * kCells, -1.0f);
    for (int b = 0; b < batch; ++b)
      for (int cell = 0; cell < kCells; ++cell) {
        const float* c = grids + (static_cast<std::size_t>(b) * kCells + cell) * voxels::kChannels;
        if (c[9] == 0) continue;
        const int label = static_cast<int>(std::lround((c[3] + 1) * 127.5f / 64));
        out.translation[static_cast<std::size_t>(b) * kCells + cell] =
            depth == 0 ? by_group[c[4] > 0 ? 1 : 0] : by_label[depth][label];
      }
    return out;
  };
  const std::vector<float> proprio = {1, 0.04f, 0.04f, 1};
  // The voxel of `point` at each depth along the path through it.
  const auto path_to = [&](const Eigen::Vector3d& first, const Eigen::Vector3d& second, const Eigen::Vector3d& third) {
    std::vector<Eigen::Vector3i> indices;
    voxels::GridBounds bounds = hierarchy.scene;
    for (const Eigen::Vector3d& p : {first, second, third}) {
      indices.push_back(bounds.index_of(p));
      if (indices.size() < 3) bounds = hierarchy.bounds_at(static_cast<int>(indices.size()), bounds.centre_of(indices.back()));
    }
    return indices;
  };

  const Choice greedy = expand(q, hierarchy, cloud, proprio, 1);
  EXPECT_EQ(greedy.indices, path_to(points[0], points[1], points[0]));  // A, a2, a1
  EXPECT_EQ(greedy.q_values, (std::vector<float>{0.625f, 0.5f, 0.75f}));
  EXPECT_EQ(greedy.value, 0.625f);  // (0.625 + (0.5 + 0.75) / 2) / 2
  EXPECT_EQ(greedy.expanded_grids, 3);

  const Choice two = expand(q, hierarchy, cloud, proprio, 2);
  EXPECT_EQ(two.indices, path_to(points[2], points[2], points[3]));  // B, b1, b2
  EXPECT_EQ(two.q_values, (std::vector<float>{0.5625f, 0.875f, 0.625f}));
  EXPECT_EQ(two.value, 0.65625f);  // (0.5625 + (0.875 + 0.625) / 2) / 2
  EXPECT_EQ(two.expanded_grids, 1 + 2 + 4);
  EXPECT_LT((two.position() - points[3]).norm(), 0.3 / V);

  // More branches only add worse ones (empty voxels, Q -1): the same choice.
  const Choice ten = expand(q, hierarchy, cloud, proprio, 10);
  EXPECT_EQ(ten.indices, two.indices);
  EXPECT_EQ(ten.value, two.value);
  EXPECT_EQ(ten.expanded_grids, 1 + 10 + 100);
  for (int k : {1, 2, 10}) expect_same_as_algorithm2(q, 3, k, cloud, true);
}

TEST(TreeExpansion, BatchedEqualsAlgorithmTwoOneBranchAtATime) {
  const Cloud cloud;
  for (int depths : {2, 3})
    for (int k : {1, 2, 5}) expect_same_as_algorithm2(test_support::content_q(), depths, k, cloud.view(), true);
}

TEST(TreeExpansion, BatchedEqualsAlgorithmTwoOnRealNetworks) {
  const Cloud cloud;
  nets::NetConfig config;  // light, 16^3, 10 channels, 4 proprio
  for (int depths : {2, 3}) {
    nets::seed_torch(5 + depths);
    const auto networks = nets::make_coarse_to_fine_nets(config, depths);
    // The batched tree defers the last depth's heads to its chosen leaf; the recursion does not.
    const DepthEvaluator every_output = [&networks](int depth, const float* grids, const float* p, int batch) {
      return networks.at(depth).predict(grids, p, batch);
    };
    for (int k : {1, 2, 5})
      expect_same_as_algorithm2(network_evaluator(networks), every_output, depths, k, cloud.view(), false);
  }
}

// The learner's tree (online networks rank, target networks value) with the last depth's heads
// deferred to the chosen leaves gives the choices, values and head values of evaluating every
// head: a batch of several observations, leaf levels over one chunk of kPredictChunk grids.
TEST(TreeExpansion, DeferredHeadsGiveTheChoicesOfEveryHead) {
  nets::NetConfig config;
  nets::seed_torch(11);
  const auto online = nets::make_coarse_to_fine_nets(config, 2), target = nets::make_coarse_to_fine_nets(config, 2);
  const auto every_output = [](const std::vector<nets::QAttentionNet>& nets) -> DepthEvaluator {
    return [&nets](int depth, const float* grids, const float* p, int batch) { return nets.at(depth).predict(grids, p, batch); };
  };
  std::vector<voxels::PointCloud> clouds;
  std::vector<std::vector<float>> proprios;
  const test_support::RandomCloud a(1, {120, 80, 40}), b(2, {40, 90, 160});
  for (int i = 0; i < 4; ++i) {
    clouds.push_back(i % 2 ? a.view() : b.view());
    proprios.push_back({1, 0.01f * i, 0.04f, 0.5f - 0.1f * i});
  }
  voxels::CoarseToFine hierarchy;
  const auto deferred = expand_batch(network_evaluator(online), network_evaluator(target), hierarchy, clouds, proprios, 10);
  const auto whole = expand_batch(every_output(online), every_output(target), hierarchy, clouds, proprios, 10);
  ASSERT_EQ(deferred.size(), whole.size());
  for (std::size_t i = 0; i < whole.size(); ++i) {
    EXPECT_EQ(deferred[i].indices, whole[i].indices) << i;
    EXPECT_EQ(deferred[i].q_values, whole[i].q_values) << i;
    EXPECT_EQ(deferred[i].value, whole[i].value) << i;
    EXPECT_EQ(deferred[i].rotation_bins, whole[i].rotation_bins) << i;
    EXPECT_EQ(deferred[i].rotation_q, whole[i].rotation_q) << i;
    EXPECT_EQ(deferred[i].gripper_open, whole[i].gripper_open) << i;
    EXPECT_EQ(deferred[i].gripper_q, whole[i].gripper_q) << i;
  }
}

// A diverged checkpoint gives NaN Q values: an error, never a path read from no branch.
TEST(TreeExpansion, NonFiniteQValuesAreAnError) {
  const Cloud cloud;
  for (int depth : {0, 1}) {
    for (float bad : {std::nanf(""), std::numeric_limits<float>::infinity()}) {
      const DepthEvaluator q = [&](int d, const float* grids, const float*, int batch) {
        nets::QValues out = test_support::content_q_values(d, grids, batch);
        if (d == depth) out.translation[batch * kCells / 2] = bad;
        return out;
      };
      try {
        expand(q, voxels::CoarseToFine{}, cloud.view(), {1, 0.04f, 0.04f, 0.5f}, 3);
        ADD_FAILURE() << "no error for " << bad << " at depth " << depth;
      } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("depth-" + std::to_string(depth) + " network gave a non-finite Q value"),
                  std::string::npos)
            << e.what();
      }
    }
  }
}

// Adaptive branching: a node expands as many voxels as its own Q volume is unsure
// about, within [1, K_max].
TEST(Branching, OneClearWinnerExpandsOneBranch) {
  std::vector<float> q(kCells, 0.0f);
  q[7] = 5.0f;
  EXPECT_EQ(branches(q.data(), kCells, Branching::within_margin(1.0f, 10)), std::vector<int>{7});
  const float small[8] = {0, 5, 0, 0, 0, 0, 0, 0};  // softmax: 0.955 on voxel 1
  EXPECT_EQ(branches(small, 8, Branching::softmax_mass(0.9f, 10)), std::vector<int>{1});
}

TEST(Branching, ThreeNearEqualVoxelsExpandThree) {
  const float q[8] = {4.9f, 0, 5.0f, 0, 4.95f, 0, 0, 0};
  EXPECT_EQ(branches(q, 8, Branching::within_margin(0.2f, 10)), (std::vector<int>{2, 4, 0}));
  // Softmax: the three hold 0.989 of the mass, the best two 0.66.
  EXPECT_EQ(branches(q, 8, Branching::softmax_mass(0.95f, 10)), (std::vector<int>{2, 4, 0}));
  EXPECT_EQ(branches(q, 8, Branching::softmax_mass(0.6f, 10)), (std::vector<int>{2, 4}));
}

TEST(Branching, BoundsOnKAreKept) {
  const float q[8] = {4.9f, 0, 5.0f, 0, 4.95f, 0, 0, 0};
  EXPECT_EQ(branches(q, 8, Branching::within_margin(0.2f, 2)), (std::vector<int>{2, 4}));     // at most K_max
  EXPECT_EQ(branches(q, 8, Branching::within_margin(100.0f, 5)).size(), 5u);                  // everything: K_max
  EXPECT_EQ(branches(q, 8, Branching::within_margin(0.0f, 5)), std::vector<int>{2});          // at least 1
  EXPECT_EQ(branches(q, 8, Branching::softmax_mass(1e-9f, 5)), std::vector<int>{2});
  EXPECT_EQ(branches(q, 8, Branching::softmax_mass(1.0f, 20)).size(), 8u);                    // no more than there are
  EXPECT_EQ(branches(q, 8, Branching(3)), top_k(q, 8, 3));                                    // fixed K: top-K
  EXPECT_THROW(branches(q, 8, Branching::within_margin(1.0f, 0)), Error);
}

// A margin no Q volume can exceed is fixed K: the same choice, the same grids, and the
// branches per depth K, K^2.
TEST(Branching, WithTheRuleOffTreeExpansionIsFixedK) {
  const Cloud cloud;
  const std::vector<float> proprio = {1, 0.04f, 0.04f, 0.5f};
  for (int depths : {2, 3}) {
    voxels::CoarseToFine hierarchy;
    hierarchy.depths = depths;
    hierarchy.offsets_m.assign(depths - 1, 0.15);
    for (int k : {1, 3}) {
      const Choice fixed = expand(test_support::content_q(), hierarchy, cloud.view(), proprio, k);
      const Choice open = expand(test_support::content_q(), hierarchy, cloud.view(), proprio,
                                 Branching::within_margin(std::numeric_limits<float>::infinity(), k));
      EXPECT_EQ(open.indices, fixed.indices);
      EXPECT_EQ(open.q_values, fixed.q_values);
      EXPECT_EQ(open.value, fixed.value);
      EXPECT_EQ(open.expanded_grids, fixed.expanded_grids);
      std::vector<int> expected;
      for (int d = 1, width = k; d < depths; ++d, width *= k) expected.push_back(width);
      EXPECT_EQ(fixed.branches, expected);
      EXPECT_EQ(open.branches, expected);
    }
  }
}

// Trees of one batch that expand different numbers of branches still go through one forward
// per depth (packed), and each chooses what it chooses alone.
TEST(Branching, AdaptiveTreesOfOneBatchChooseAsAlone) {
  const float kMargin = 0.01f;  // content_q's volumes are dense near their best: 10, 10 and 6 within it
  const voxels::CoarseToFine hierarchy;
  std::vector<test_support::RandomCloud> clouds;
  for (uint32_t seed : {1u, 2u, 3u}) clouds.emplace_back(seed, std::array<uint8_t, 3>{120, 80, 40});
  std::vector<voxels::PointCloud> views;
  for (const auto& c : clouds) views.push_back(c.view());
  const std::vector<std::vector<float>> proprios(3, std::vector<float>{1, 0.04f, 0.04f, 0.5f});
  const Branching adaptive = Branching::within_margin(kMargin, 10);
  int calls = 0;
  const DepthEvaluator counted = [&](int depth, const float* grids, const float* p, int batch) {
    calls += 1;
    return test_support::content_q()(depth, grids, p, batch);
  };
  const auto together = expand_batch(counted, hierarchy, views, proprios, adaptive);
  EXPECT_EQ(calls, 2);
  std::set<int> counts;
  for (int i = 0; i < 3; ++i) {
    const Choice alone = expand(test_support::content_q(), hierarchy, views[i], proprios[i], adaptive);
    EXPECT_EQ(together[i].indices, alone.indices) << i;
    EXPECT_EQ(together[i].value, alone.value) << i;
    EXPECT_EQ(together[i].branches, alone.branches) << i;
    // Depth 0's branches: the voxels of its volume within the margin, counted here directly.
    std::vector<float> grid(static_cast<std::size_t>(kCells) * voxels::kChannels);
    voxels::voxelize(views[i], hierarchy.scene, grid.data());
    const nets::QValues q0 = test_support::content_q()(0, grid.data(), proprios[i].data(), 1);
    const float best = *std::max_element(q0.translation.begin(), q0.translation.end());
    const int within = static_cast<int>(std::count_if(q0.translation.begin(), q0.translation.end(),
                                                      [&](float x) { return x >= best - kMargin; }));
    EXPECT_EQ(alone.branches[0], std::clamp(within, 1, 10)) << i;
    counts.insert(alone.branches[0]);
  }
  EXPECT_EQ(together[0].expanded_grids, 3 + together[0].branches[0] + together[1].branches[0] + together[2].branches[0]);
  EXPECT_GT(counts.size(), 1u) << "the three scenes should need different numbers of branches";
}

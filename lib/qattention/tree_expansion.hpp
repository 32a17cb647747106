// Q-attention with Tree Expansion (QTE, the paper's Algorithm 2), batched. At each non-leaf
// depth the top-K voxels of every branch's Q volume are expanded: the next depth's grids
// around all of them are voxelized in one pass over the cloud and evaluated in one batched
// forward. A branch's value is (q_k + q'_k) / 2, q'_k being what the deeper level returns (at
// the leaf, its volume's max Q); each level returns its best branch's value, and the agent
// acts on the best path. K = 1 is exactly C2F-ARM's greedy coarse-to-fine choice.
//
// The learner's bootstrap target is the same tree with two sets of networks, as published
// (double DQN over the tree): the online networks rank the top-K voxels of every non-leaf
// grid and pick the leaf voxel and the heads' bins; the target networks value those indices,
// and branch values and the max over branches are taken on the target networks' values.
#pragma once

#include <Eigen/Core>
#include <functional>
#include <vector>

#include "nets/qattention_net.hpp"
#include "voxels/voxel_grid.hpp"

namespace qte::qattention {

// Evaluates `batch` grids (channels last, [batch, V, V, V, C]) at `depth` with one proprio
// vector for all of them; QAttentionNet::predict_leaves of that depth's network in production
// (at the last depth the heads may come later, through QValues::heads_for, for the chosen leaves).
using DepthEvaluator =
    std::function<nets::QValues(int depth, const float* grids, const float* proprio, int batch)>;

// How many of a node's voxels become branches. Fixed: the K best (K = 1: greedy). Adaptive
// (the paper's open question of choosing K): the node's own Q volume decides, expanding more
// where it is unsure — every voxel within `margin` of its best Q, or the fewest best voxels
// holding `mass` of its softmax — at least 1, at most `k` (then K_max).
struct Branching {
  enum class Rule { fixed, margin, mass };
  Rule rule = Rule::fixed;
  int k = 1;
  float threshold = 0;  // margin: Q units; mass: a share in (0, 1]
  Branching(int fixed_k = 1) : k(fixed_k) {}  // NOLINT: an int is a fixed K
  static Branching within_margin(float margin, int k_max);
  static Branching softmax_mass(float mass, int k_max);
  bool adaptive() const { return rule != Rule::fixed; }
};

// The branches of one Q volume (flat indices, best first, ties to the lower index).
std::vector<int> branches(const float* q, int count, const Branching& branching);

struct Choice {
  std::vector<Eigen::Vector3i> indices;       // per depth
  // Per non-leaf depth, the best-ranked voxel of the grid the path passes through there (at
  // depth 0, the argmax of depth 0's Q): where K = 1 would go from that grid. It differs from
  // `indices` where a finer depth overruled the coarse choice.
  std::vector<Eigen::Vector3i> argmax_indices;
  std::vector<voxels::GridBounds> bounds;     // per depth
  std::vector<float> q_values;                // the chosen voxel's Q, per depth (valuing networks)
  float value = 0;                            // the tree's value of the choice
  Eigen::Vector3i rotation_bins = Eigen::Vector3i::Zero();
  bool gripper_open = true;
  Eigen::Vector3f rotation_q = Eigen::Vector3f::Zero();  // the chosen bins' Q values
  float gripper_q = 0;                                   // the chosen gripper action's Q value
  int expanded_grids = 0;                     // grids evaluated, all observations (1 + K + K^2 + ...)
  std::vector<int> branches;                  // per non-leaf depth: this tree's nodes expanded there
  Eigen::Vector3d position() const { return bounds.back().centre_of(indices.back()); }
};

// A branch's value: its voxel's Q and the value the deeper level returns, averaged (Algorithm 2).
inline float branch_value(float q, float deeper_value) { return (q + deeper_value) / 2; }

// The K best voxels of one Q volume (flat indices, best first, ties to the lower index).
std::vector<int> top_k(const float* q, int count, int k);

// Branches per non-leaf grid as `branching` says (k = 1: greedy). The last depth's gripper Q
// values are (close, open), as the transitions' gripper_open 0 / 1.
Choice expand(const DepthEvaluator& evaluate, const voxels::CoarseToFine& hierarchy,
              const voxels::PointCloud& cloud, const std::vector<float>& proprio, const Branching& branching);

// Tree expansion of several observations at once (the learner's bootstrap targets): every
// depth's grids of all of them go through one batched forward (packed: with an adaptive rule
// trees expand different numbers of branches, and a level holds just the nodes there are).
// `proprios[i]` belongs to `clouds[i]`; the choices come back in the same order.
std::vector<Choice> expand_batch(const DepthEvaluator& evaluate, const voxels::CoarseToFine& hierarchy,
                                 const std::vector<voxels::PointCloud>& clouds,
                                 const std::vector<std::vector<float>>& proprios, const Branching& branching);

// The same with indices from `rank` (the online networks) and values from `value` (the target
// networks), both evaluated on the grids `rank`'s choices lead to: the published target.
std::vector<Choice> expand_batch(const DepthEvaluator& rank, const DepthEvaluator& value,
                                 const voxels::CoarseToFine& hierarchy, const std::vector<voxels::PointCloud>& clouds,
                                 const std::vector<std::vector<float>>& proprios, const Branching& branching);

// Throws Error when a network's output holds NaN or infinity (a diverged checkpoint, or a
// non-finite input that reached the network): a max over NaN picks nothing.
void check_finite(const nets::QValues& q, int depth);

// The evaluator of a set of networks, one per depth.
DepthEvaluator network_evaluator(const std::vector<nets::QAttentionNet>& nets);

}  // namespace qte::qattention

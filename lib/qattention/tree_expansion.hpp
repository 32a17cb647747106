// Q-attention with Tree Expansion (QTE, the paper's Algorithm 2), batched. At each non-leaf
// depth the top-K voxels of every branch's Q volume are expanded: the next depth's grids
// around all of them are voxelized in one pass over the cloud and evaluated in one batched
// forward. A branch's value is (q_k + q'_k) / 2, q'_k being what the deeper level returns (at
// the leaf, its volume's max Q); each level returns its best branch's value, and the agent
// acts on the best path. K = 1 is exactly C2F-ARM's greedy coarse-to-fine choice.
#pragma once

#include <Eigen/Core>
#include <functional>
#include <vector>

#include "nets/qattention_net.hpp"
#include "voxels/voxel_grid.hpp"

namespace qte::qattention {

// Evaluates `batch` grids (channels last, [batch, V, V, V, C]) at `depth` with one proprio
// vector for all of them; QAttentionNet::predict of that depth's network in production.
using DepthEvaluator =
    std::function<nets::QValues(int depth, const float* grids, const float* proprio, int batch)>;

struct Choice {
  std::vector<Eigen::Vector3i> indices;       // per depth
  std::vector<voxels::GridBounds> bounds;     // per depth
  std::vector<float> q_values;                // the chosen voxel's Q, per depth
  float value = 0;                            // the tree's value of the choice
  Eigen::Vector3i rotation_bins = Eigen::Vector3i::Zero();
  bool gripper_open = true;
  Eigen::Vector3f rotation_q = Eigen::Vector3f::Zero();  // the chosen bins' Q values
  float gripper_q = 0;                                   // the chosen gripper action's Q value
  int expanded_grids = 0;                     // grids evaluated (1 + K + K^2 + ...)
  Eigen::Vector3d position() const { return bounds.back().centre_of(indices.back()); }
};

// The K best voxels of one Q volume (flat indices, best first, ties to the lower index).
std::vector<int> top_k(const float* q, int count, int k);

// `k` branches per non-leaf depth (k = 1: greedy). The last depth's gripper Q values are
// (close, open), as the transitions' gripper_open 0 / 1.
Choice expand(const DepthEvaluator& evaluate, const voxels::CoarseToFine& hierarchy,
              const voxels::PointCloud& cloud, const std::vector<float>& proprio, int k);

// Tree expansion of several observations at once (the learner's bootstrap targets): every
// depth's grids of all of them go through one batched forward. `proprios[i]` belongs to
// `clouds[i]`; the choices come back in the same order.
std::vector<Choice> expand_batch(const DepthEvaluator& evaluate, const voxels::CoarseToFine& hierarchy,
                                 const std::vector<voxels::PointCloud>& clouds,
                                 const std::vector<std::vector<float>>& proprios, int k);

// The evaluator of a set of networks, one per depth.
DepthEvaluator network_evaluator(const std::vector<nets::QAttentionNet>& nets);

}  // namespace qte::qattention

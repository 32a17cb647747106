#include "qattention/tree_expansion.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "common/error.hpp"

namespace qte::qattention {

std::vector<int> top_k(const float* q, int count, int k) {
  std::vector<int> order(count);
  std::iota(order.begin(), order.end(), 0);
  k = std::min(k, count);
  std::partial_sort(order.begin(), order.begin() + k, order.end(),
                    [&](int a, int b) { return q[a] > q[b] || (q[a] == q[b] && a < b); });
  order.resize(k);
  return order;
}

Branching Branching::within_margin(float margin, int k_max) {
  Branching b(k_max);
  b.rule = Rule::margin;
  b.threshold = margin;
  return b;
}

Branching Branching::softmax_mass(float mass, int k_max) {
  Branching b(k_max);
  b.rule = Rule::mass;
  b.threshold = mass;
  return b;
}

std::vector<int> branches(const float* q, int count, const Branching& branching) {
  if (branching.k < 1) throw Error("tree expansion needs k >= 1");
  std::vector<int> best = top_k(q, count, branching.k);
  if (branching.rule == Branching::Rule::margin) {
    std::size_t keep = 1;
    while (keep < best.size() && q[best[keep]] >= q[best[0]] - branching.threshold) ++keep;
    best.resize(keep);
  } else if (branching.rule == Branching::Rule::mass) {
    // Softmax over the whole volume, shifted by its max (no overflow).
    double total = 0;
    for (int i = 0; i < count; ++i) total += std::exp(static_cast<double>(q[i]) - q[best[0]]);
    std::size_t keep = 0;
    double held = 0;
    while (keep < best.size() && (keep == 0 || held < branching.threshold * total))
      held += std::exp(static_cast<double>(q[best[keep++]]) - q[best[0]]);
    best.resize(keep);
  }
  return best;
}

namespace {

int argmax(const float* q, int count) { return top_k(q, count, 1)[0]; }

}  // namespace

Choice expand(const DepthEvaluator& evaluate, const voxels::CoarseToFine& hierarchy,
              const voxels::PointCloud& cloud, const std::vector<float>& proprio, const Branching& branching) {
  return expand_batch(evaluate, hierarchy, {cloud}, {proprio}, branching).front();
}

void check_finite(const nets::QValues& q, int depth) {
  for (const std::vector<float>* values : {&q.translation, &q.rotation, &q.gripper})
    for (float x : *values)
      if (!std::isfinite(x))
        throw Error("the depth-" + std::to_string(depth) + " network gave a non-finite Q value (" + std::to_string(x) +
                    "): a diverged checkpoint, or a non-finite input");
}

std::vector<Choice> expand_batch(const DepthEvaluator& evaluate, const voxels::CoarseToFine& hierarchy,
                                 const std::vector<voxels::PointCloud>& clouds,
                                 const std::vector<std::vector<float>>& proprios, const Branching& branching) {
  return expand_batch(evaluate, nullptr, hierarchy, clouds, proprios, branching);
}

namespace {

// The trees of a batch, level by level: every node's grid, its observation, its parent and the
// voxel of the parent it expands. Children are appended in their parents' order, so each
// level's nodes are grouped by observation. Per depth, the ranking networks' outputs and the
// valuing networks' (none when one set of networks both ranks and values).
struct Node {
  voxels::GridBounds bounds;
  int observation = 0;
  int parent = -1;
  int parent_voxel = -1;
};
struct Trees {
  std::vector<std::vector<Node>> levels;
  std::vector<nets::QValues> ranked, valued;
  bool separate_values = false;
  int expanded_grids = 0;
  const std::vector<nets::QValues>& values() const { return separate_values ? valued : ranked; }
};

// One level's grids through the networks: voxelized with one pass over each observation's
// points for all its grids, then one forward of each set of networks.
void evaluate_level(const DepthEvaluator& rank, const DepthEvaluator& value_of, int d, int cells,
                    const std::vector<voxels::PointCloud>& clouds, const std::vector<std::vector<float>>& proprios,
                    Trees& trees) {
  const std::vector<Node>& level = trees.levels[d];
  const int n = static_cast<int>(level.size());
  const std::size_t grid_floats = static_cast<std::size_t>(cells) * voxels::kChannels;
  std::vector<float> batch(grid_floats * n);
  std::vector<float> proprio_batch;
  for (int first = 0; first < n;) {
    int last = first;
    std::vector<voxels::GridBounds> grids;
    while (last < n && level[last].observation == level[first].observation) grids.push_back(level[last++].bounds);
    voxels::voxelize_many(clouds[level[first].observation], grids, batch.data() + first * grid_floats);
    first = last;
  }
  for (const Node& node : level)
    proprio_batch.insert(proprio_batch.end(), proprios[node.observation].begin(), proprios[node.observation].end());
  trees.ranked[d] = rank(d, batch.data(), proprio_batch.data(), n);
  if (value_of) trees.valued[d] = value_of(d, batch.data(), proprio_batch.data(), n);
  for (const nets::QValues* q : {&trees.ranked[d], value_of ? &trees.valued[d] : nullptr}) {
    if (!q) continue;
    if (static_cast<int>(q->translation.size()) != n * cells)
      throw Error("tree expansion: depth " + std::to_string(d) + " returned the wrong number of Q values");
    check_finite(*q, d);
  }
  trees.expanded_grids += n;
}

// Grows the trees depth by depth: each level evaluated, each node's branches the next level.
Trees grow(const DepthEvaluator& rank, const DepthEvaluator& value_of, const voxels::CoarseToFine& hierarchy,
           const std::vector<voxels::PointCloud>& clouds, const std::vector<std::vector<float>>& proprios,
           const Branching& branching) {
  const int depths = hierarchy.depths, v = hierarchy.voxels(), cells = v * v * v;
  Trees trees;
  trees.levels.resize(depths);
  trees.ranked.resize(depths);
  trees.valued.resize(depths);
  trees.separate_values = static_cast<bool>(value_of);
  for (std::size_t i = 0; i < clouds.size(); ++i) trees.levels[0].push_back({hierarchy.scene, static_cast<int>(i), -1, -1});
  for (int d = 0; d < depths; ++d) {
    evaluate_level(rank, value_of, d, cells, clouds, proprios, trees);
    if (d + 1 == depths) break;
    const std::vector<Node>& level = trees.levels[d];
    for (std::size_t i = 0; i < level.size(); ++i)
      for (int flat : branches(trees.ranked[d].translation.data() + i * cells, cells, branching))
        trees.levels[d + 1].push_back({hierarchy.bounds_at(d + 1, level[i].bounds.centre_of(voxels::index_from_flat(flat, v))),
                                       level[i].observation, static_cast<int>(i), flat});
  }
  return trees;
}

// Values bottom-up: a leaf is worth the value of its best-ranked voxel (its max Q when one set
// of networks ranks and values); a node's value through child c is (q of c's voxel + c's
// value) / 2, and the node is worth its best child.
struct Backup {
  std::vector<std::vector<float>> value;
  std::vector<std::vector<int>> best_child;
};

Backup back_up(const Trees& trees, int cells) {
  const int depths = static_cast<int>(trees.levels.size()), leaf = depths - 1;
  const std::vector<nets::QValues>& outputs = trees.values();
  Backup b{std::vector<std::vector<float>>(depths), std::vector<std::vector<int>>(depths)};
  for (std::size_t i = 0; i < trees.levels[leaf].size(); ++i) {
    const float* q = trees.ranked[leaf].translation.data() + i * cells;
    b.value[leaf].push_back(outputs[leaf].translation[i * cells + argmax(q, cells)]);
  }
  for (int d = leaf - 1; d >= 0; --d) {
    b.value[d].assign(trees.levels[d].size(), -1e30f);
    b.best_child[d].assign(trees.levels[d].size(), -1);
    for (std::size_t c = 0; c < trees.levels[d + 1].size(); ++c) {
      const Node& child = trees.levels[d + 1][c];
      const float q = outputs[d].translation[static_cast<std::size_t>(child.parent) * cells + child.parent_voxel];
      const float through = branch_value(q, b.value[d + 1][c]);
      if (through > b.value[d][child.parent]) {  // strict: the earlier (higher-ranked) child wins ties
        b.value[d][child.parent] = through;
        b.best_child[d][child.parent] = static_cast<int>(c);
      }
    }
  }
  return b;
}

// The dense heads of the leaves the paths end in, where the evaluators left them for later
// (QValues::heads_for: a leaf level's heads are needed only for the chosen leaves).
void heads_of_chosen_leaves(Trees& trees, const std::vector<int>& leaves) {
  const int leaf = static_cast<int>(trees.levels.size()) - 1;
  for (nets::QValues* q : {&trees.ranked[leaf], trees.separate_values ? &trees.valued[leaf] : nullptr}) {
    if (!q || !q->heads_for) continue;
    q->heads_for(leaves, *q);
    q->heads_for = nullptr;  // lets the kept activations go
    check_finite(*q, leaf);
  }
}

// Each tree's best path from its root: per depth the voxel, its grid and Q; at the leaf the
// ranking networks' rotation bins and gripper action; the nodes each depth below the root had.
std::vector<Choice> best_paths(Trees& trees, const Backup& backup, int voxels_per_side, std::size_t roots) {
  const int depths = static_cast<int>(trees.levels.size()), leaf = depths - 1;
  const int cells = voxels_per_side * voxels_per_side * voxels_per_side;
  const std::vector<nets::QValues>& outputs = trees.values();
  std::vector<Choice> choices(roots);
  for (int d = 1; d < depths; ++d) {
    for (Choice& c : choices) c.branches.push_back(0);
    for (const Node& node : trees.levels[d]) choices[node.observation].branches.back() += 1;
  }
  std::vector<int> leaves(roots);
  for (std::size_t root = 0; root < roots; ++root) {
    Choice& choice = choices[root];
    choice.expanded_grids = trees.expanded_grids;
    int node = static_cast<int>(root);
    choice.value = backup.value[0][node];
    for (int d = 0; d < depths; ++d) {
      const std::size_t at = static_cast<std::size_t>(node) * cells;
      const int voxel = d + 1 < depths ? trees.levels[d + 1][backup.best_child[d][node]].parent_voxel
                                       : argmax(trees.ranked[d].translation.data() + at, cells);
      choice.indices.push_back(voxels::index_from_flat(voxel, voxels_per_side));
      if (d + 1 < depths)
        choice.argmax_indices.push_back(
            voxels::index_from_flat(argmax(trees.ranked[d].translation.data() + at, cells), voxels_per_side));
      choice.bounds.push_back(trees.levels[d][node].bounds);
      choice.q_values.push_back(outputs[d].translation[at + voxel]);
      if (d + 1 < depths) node = backup.best_child[d][node];
    }
    leaves[root] = node;
  }
  heads_of_chosen_leaves(trees, leaves);
  if (trees.ranked[leaf].rotation.empty()) return choices;
  for (std::size_t root = 0; root < roots; ++root) {
    Choice& choice = choices[root];
    const int node = leaves[root];
    const std::size_t r = static_cast<std::size_t>(node) * nets::kRotationAxes * nets::kRotationBins;
    for (int axis = 0; axis < nets::kRotationAxes; ++axis) {
      const std::size_t at = r + axis * nets::kRotationBins;
      choice.rotation_bins[axis] = argmax(trees.ranked[leaf].rotation.data() + at, nets::kRotationBins);
      choice.rotation_q[axis] = outputs[leaf].rotation[at + choice.rotation_bins[axis]];
    }
    const std::size_t g = static_cast<std::size_t>(node) * nets::kGripperActions;
    const int open = argmax(trees.ranked[leaf].gripper.data() + g, nets::kGripperActions);
    choice.gripper_open = open == 1;  // index 1 = open, as the transitions' gripper_open
    choice.gripper_q = outputs[leaf].gripper[g + open];
  }
  return choices;
}

}  // namespace

std::vector<Choice> expand_batch(const DepthEvaluator& rank, const DepthEvaluator& value_of,
                                 const voxels::CoarseToFine& hierarchy, const std::vector<voxels::PointCloud>& clouds,
                                 const std::vector<std::vector<float>>& proprios, const Branching& branching) {
  if (branching.k < 1) throw Error("tree expansion needs k >= 1");
  if (clouds.size() != proprios.size() || clouds.empty())
    throw Error("tree expansion needs one proprio vector per point cloud");
  const int v = hierarchy.voxels();
  Trees trees = grow(rank, value_of, hierarchy, clouds, proprios, branching);
  return best_paths(trees, back_up(trees, v * v * v), v, clouds.size());
}

DepthEvaluator network_evaluator(const std::vector<nets::QAttentionNet>& nets) {
  // The last depth's heads wait until the tree has chosen its leaves (see best_paths).
  return [&nets](int depth, const float* grids, const float* proprio, int batch) {
    return nets.at(depth).predict_leaves(grids, proprio, batch);
  };
}

}  // namespace qte::qattention

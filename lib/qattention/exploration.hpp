// Exploration of the acting agent: the tree-expanded choice changed at random, per depth a
// uniformly random voxel (the deeper depths chosen again below it by tree expansion), noise on
// the last depth's voxel index and on the rotation bins, and gripper flips.
#pragma once

#include <random>
#include <vector>

#include "qattention/tree_expansion.hpp"

namespace qte::qattention {

struct Exploration {
  double epsilon = 0;         // per depth: a random voxel instead of the chosen one
  double index_noise = 0;     // voxels, on the last depth's index
  double rotation_noise = 0;  // bins
  double gripper_flip = 0;    // probability
};

// `chosen` changed by `exploration`, the random choices drawn from `rng` (nothing is drawn for
// a setting that is 0, so Exploration{} returns `chosen` and leaves `rng` as it was).
struct Explored {
  Choice choice;
  // Per depth: the voxel was put in by exploration, so its Q-value in `choice` is still the
  // voxel's it replaced.
  std::vector<bool> replaced;
};

// `evaluate`, `hierarchy`, `cloud`, `proprio` and `branching` are those `chosen` was expanded with:
// the depths below a random voxel are chosen again with them.
Explored explore(const Choice& chosen, const Exploration& exploration, std::mt19937_64& rng,
                 const DepthEvaluator& evaluate, const voxels::CoarseToFine& hierarchy,
                 const voxels::PointCloud& cloud, const std::vector<float>& proprio, const Branching& branching);

// The same pose and gripper command: the same voxels, rotation bins and gripper_open.
bool same_action(const Choice& a, const Choice& b);

}  // namespace qte::qattention

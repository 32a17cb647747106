#include "qattention/exploration.hpp"

#include <algorithm>
#include <cmath>

namespace qte::qattention {

Explored explore(const Choice& chosen, const Exploration& exploration, std::mt19937_64& rng,
                 const DepthEvaluator& evaluate, const voxels::CoarseToFine& hierarchy,
                 const voxels::PointCloud& cloud, const std::vector<float>& proprio, const Branching& branching) {
  Explored explored{chosen, {}};
  Choice& c = explored.choice;
  std::vector<bool>& replaced = explored.replaced;
  const int depths = hierarchy.depths, v = hierarchy.voxels();
  replaced.assign(depths, false);
  if (exploration.epsilon > 0) {
    std::bernoulli_distribution random_voxel(exploration.epsilon);
    std::uniform_int_distribution<int> any_index(0, v - 1);
    for (int d = 0; d < depths; ++d) {
      if (!random_voxel(rng)) continue;
      const int x = any_index(rng), y = any_index(rng), z = any_index(rng);
      c.indices[d] = Eigen::Vector3i(x, y, z);
      replaced[d] = true;
      if (d + 1 == depths) break;
      // The depths below, chosen again by tree expansion around the random voxel: a
      // hierarchy whose scene is the next depth's grid, evaluated by the deeper networks.
      const voxels::CoarseToFine below = hierarchy.below(d, c.bounds[d].centre_of(c.indices[d]));
      const DepthEvaluator deeper_nets = [&evaluate, d](int j, const float* grids, const float* p, int batch) {
        return evaluate(j + d + 1, grids, p, batch);
      };
      const Choice deeper = expand(deeper_nets, below, cloud, proprio, branching);
      for (int j = 0; j + d + 1 < depths; ++j) {
        c.indices[j + d + 1] = deeper.indices[j];
        c.bounds[j + d + 1] = deeper.bounds[j];
        c.q_values[j + d + 1] = deeper.q_values[j];
        if (j + d + 1 < static_cast<int>(c.argmax_indices.size())) c.argmax_indices[j + d + 1] = deeper.argmax_indices[j];
        replaced[j + d + 1] = false;
      }
      c.rotation_bins = deeper.rotation_bins;
      c.gripper_open = deeper.gripper_open;
      c.expanded_grids += deeper.expanded_grids;
    }
  }
  if (exploration.index_noise > 0) {
    std::normal_distribution<double> noise(0, exploration.index_noise);
    Eigen::Vector3i& last = c.indices.back();
    const Eigen::Vector3i before = last;
    for (int axis = 0; axis < 3; ++axis)
      last[axis] = static_cast<int>(std::clamp<long>(std::lround(last[axis] + noise(rng)), 0, v - 1));
    if (last != before) replaced.back() = true;
  }
  if (exploration.rotation_noise > 0) {
    std::normal_distribution<double> noise(0, exploration.rotation_noise);
    for (int axis = 0; axis < 3; ++axis) {
      const long bin = c.rotation_bins[axis] + std::lround(noise(rng));
      c.rotation_bins[axis] = static_cast<int>((bin % nets::kRotationBins + nets::kRotationBins) % nets::kRotationBins);
    }
  }
  if (exploration.gripper_flip > 0 && std::bernoulli_distribution(exploration.gripper_flip)(rng))
    c.gripper_open = !c.gripper_open;
  return explored;
}

bool same_action(const Choice& a, const Choice& b) {
  return a.indices == b.indices && a.rotation_bins == b.rotation_bins && a.gripper_open == b.gripper_open;
}

}  // namespace qte::qattention

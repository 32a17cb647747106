// Acting: the networks of a checkpoint file (loaded again when the learner replaces it), the
// action for one observation (tree expansion, then exploration), and what is kept of it: the
// Q-values of the grids along its path as pictures.
#pragma once

#include <sys/types.h>

#include <cstdint>
#include <ctime>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "nets/checkpoint.hpp"
#include "qattention/exploration.hpp"
#include "qattention/tree_expansion.hpp"

namespace qte::qattention {

// The networks of a checkpoint file, one per depth. Checks that they take what the actor
// gives them: voxels::kChannels channels per voxel and kProprio proprioception inputs.
class CheckpointNetworks {
 public:
  explicit CheckpointNetworks(const std::string& path);
  CheckpointNetworks(const CheckpointNetworks&) = delete;  // evaluators refer to nets()
  CheckpointNetworks& operator=(const CheckpointNetworks&) = delete;

  // Loads the file again when it is not the version loaded (the learner replaces its
  // checkpoint by an atomic rename); true when it did. The configuration must not change.
  bool reload_if_changed();

  const std::string& path() const { return path_; }
  const nets::CheckpointConfig& config() const { return config_; }
  const std::vector<nets::QAttentionNet>& nets() const { return nets_; }
  int64_t step() const { return step_; }  // the training step of the weights loaded
  // The scene bounds and offsets the networks were trained on (a learner's checkpoint keeps
  // them); nothing for a checkpoint of networks only.
  const std::optional<voxels::CoarseToFine>& hierarchy() const { return hierarchy_; }

 private:
  // What identifies one version of a file on disk: a replacement renamed into place has
  // another inode, and a rewrite another size or modification time.
  struct FileVersion {
    dev_t device = 0;
    ino_t inode = 0;
    off_t size = 0;
    timespec modified{};
    bool operator==(const FileVersion& o) const;
  };
  static FileVersion version_of(const std::string& path);

  std::string path_;
  FileVersion version_;
  nets::CheckpointConfig config_;
  std::optional<voxels::CoarseToFine> hierarchy_;
  std::vector<nets::QAttentionNet> nets_;
  int64_t step_ = 0;
};

// One grid voxelized and evaluated alone: its voxels (voxels::voxelize's layout) and their Q.
struct GridQ {
  std::vector<float> grid, q;
};

GridQ evaluate_grid(const DepthEvaluator& evaluate, int depth, const voxels::GridBounds& bounds,
                    const voxels::PointCloud& cloud, const std::vector<float>& proprio);

// The grids along one path, each evaluated alone the first time it is asked for (for
// pictures, and for the Q of a voxel that exploration put in place of the chosen one).
// `cloud`'s points must outlive it.
class PathGrids {
 public:
  PathGrids(DepthEvaluator evaluate, const voxels::PointCloud& cloud, std::vector<float> proprio,
            std::vector<voxels::GridBounds> bounds);
  const GridQ& at(int depth);

 private:
  DepthEvaluator evaluate_;
  voxels::PointCloud cloud_;
  std::vector<float> proprio_;
  std::vector<voxels::GridBounds> bounds_;
  std::vector<std::optional<GridQ>> grids_;
};

// What the agent does after one observation.
struct Action {
  // The tree's choice, or what exploration made of it; then the Q-values are those of the
  // voxels taken and the value is the path's as the tree values its best path.
  Choice choice;
  bool explored = false;  // exploration changed the pose or the gripper command
  PathGrids grids;        // along choice's path
};

// Tree expansion as `branching` says, then `exploration` drawing from `rng`. The action's
// choice reports the tree's branches per depth even when exploration replaced a voxel.
Action act(const DepthEvaluator& evaluate, const voxels::CoarseToFine& hierarchy, const voxels::PointCloud& cloud,
           const std::vector<float>& proprio, const Branching& branching, const Exploration& exploration,
           std::mt19937_64& rng);

// Saves a picture of every depth's grid along the action's path as DIR/<index>.depth<d>.png
// (index from 000000): the occupied voxels coloured by Q, the chosen voxel outlined in red.
void save_q_pictures(const std::string& dir, uint64_t index, Action& action);

}  // namespace qte::qattention

#include "qattention/acting.hpp"

#include <sys/stat.h>

#include <cstdio>
#include <limits>
#include <utility>

#include "common/error.hpp"
#include "common/indexed_name.hpp"
#include "qattention/proprio.hpp"
#include "stream/reader.hpp"
#include "voxels/grid_fields.hpp"
#include "voxels/voxel_image.hpp"

namespace qte::qattention {

namespace {

constexpr int kOccupancyChannel = voxels::kChannels - 1;  // 1 when the voxel holds a point

// The value of a path as the tree values its best path: from the last depth up, each depth
// worth (its voxel's Q + the value below) / 2.
float path_value(const std::vector<float>& q_values) {
  float value = q_values.back();
  for (int d = static_cast<int>(q_values.size()) - 2; d >= 0; --d) value = branch_value(q_values[d], value);
  return value;
}

}  // namespace

bool CheckpointNetworks::FileVersion::operator==(const FileVersion& o) const {
  return device == o.device && inode == o.inode && size == o.size && modified.tv_sec == o.modified.tv_sec &&
         modified.tv_nsec == o.modified.tv_nsec;
}

CheckpointNetworks::FileVersion CheckpointNetworks::version_of(const std::string& path) {
  struct stat s {};
  if (::stat(path.c_str(), &s) != 0) throw_system_error("cannot open " + path);
  return {s.st_dev, s.st_ino, s.st_size, s.st_mtim};
}

CheckpointNetworks::CheckpointNetworks(const std::string& path) : path_(path) {
  version_ = version_of(path_);
  const stream::Record record = nets::read_online_checkpoint(path_);
  config_ = nets::checkpoint_config(record);
  if (config_.net.channels != voxels::kChannels)
    throw Error(path_ + ": the networks take " + std::to_string(config_.net.channels) +
                " channels per voxel; qte-select voxelizes " + std::to_string(voxels::kChannels));
  if (config_.net.proprio != kProprio)
    throw Error(path_ + ": the networks take " + std::to_string(config_.net.proprio) +
                " proprioception inputs; qte-select gives " + std::to_string(kProprio));
  hierarchy_ = voxels::hierarchy_of(record);
  nets_ = nets::make_coarse_to_fine_nets(config_.net, config_.depths);
  step_ = nets::load_checkpoint_record(record, nets_, nullptr);
}

bool CheckpointNetworks::reload_if_changed() {
  const FileVersion now = version_of(path_);
  if (now == version_) return false;
  step_ = nets::load_checkpoint_record(nets::read_online_checkpoint(path_), nets_, nullptr);  // checks the configuration
  version_ = now;
  return true;
}

GridQ evaluate_grid(const DepthEvaluator& evaluate, int depth, const voxels::GridBounds& bounds,
                    const voxels::PointCloud& cloud, const std::vector<float>& proprio) {
  GridQ g;
  g.grid.resize(static_cast<std::size_t>(bounds.voxels) * bounds.voxels * bounds.voxels * voxels::kChannels);
  voxels::voxelize(cloud, bounds, g.grid.data());
  g.q = evaluate(depth, g.grid.data(), proprio.data(), 1).translation;
  return g;
}

PathGrids::PathGrids(DepthEvaluator evaluate, const voxels::PointCloud& cloud, std::vector<float> proprio,
                     std::vector<voxels::GridBounds> bounds)
    : evaluate_(std::move(evaluate)),
      cloud_(cloud),
      proprio_(std::move(proprio)),
      bounds_(std::move(bounds)),
      grids_(bounds_.size()) {}

const GridQ& PathGrids::at(int depth) {
  std::optional<GridQ>& g = grids_.at(depth);
  if (!g) g = evaluate_grid(evaluate_, depth, bounds_[depth], cloud_, proprio_);
  return *g;
}

Action act(const DepthEvaluator& evaluate, const voxels::CoarseToFine& hierarchy, const voxels::PointCloud& cloud,
           const std::vector<float>& proprio, const Branching& branching, const Exploration& exploration,
           std::mt19937_64& rng) {
  const Choice chosen = expand(evaluate, hierarchy, cloud, proprio, branching);
  const Explored explored = explore(chosen, exploration, rng, evaluate, hierarchy, cloud, proprio, branching);
  const bool changed = !same_action(explored.choice, chosen);
  const Choice& taken = changed ? explored.choice : chosen;
  Action action{taken, changed, PathGrids(evaluate, cloud, proprio, taken.bounds)};
  action.choice.branches = chosen.branches;
  if (changed) {
    Choice& c = action.choice;
    for (int d = 0; d < hierarchy.depths; ++d)
      if (explored.replaced[d]) c.q_values[d] = action.grids.at(d).q[voxels::flat_index(c.indices[d], hierarchy.voxels())];
    c.value = path_value(c.q_values);
  }
  return action;
}

void save_q_pictures(const std::string& dir, uint64_t index, Action& action) {
  const Choice& c = action.choice;
  for (int d = 0; d < static_cast<int>(c.indices.size()); ++d) {
    const GridQ& g = action.grids.at(d);
    const int v = c.bounds[d].voxels;
    const int chosen_voxel = voxels::flat_index(c.indices[d], v);
    voxels::VoxelImageOptions picture;
    picture.min_value = std::numeric_limits<float>::lowest();
    picture.values.assign(g.q.size(), picture.min_value);  // empty voxels are not drawn
    for (std::size_t i = 0; i < g.q.size(); ++i)
      if (g.grid[i * voxels::kChannels + kOccupancyChannel] > 0 || static_cast<int>(i) == chosen_voxel)
        picture.values[i] = g.q[i];
    picture.marked_x = c.indices[d].x();
    picture.marked_y = c.indices[d].y();
    picture.marked_z = c.indices[d].z();
    voxels::save_voxel_png(dir + "/" + indexed_name(index, "depth" + std::to_string(d) + ".png"), g.grid.data(), v,
                           picture);
  }
}

}  // namespace qte::qattention

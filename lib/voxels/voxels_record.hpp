// The 'voxels' record voxelize writes after each observation (formats/record-stream.md):
// depth0.grid [V, V, V, C] over the scene bounds and depth0.bounds; with crops, depth1.grid
// [K, V, V, V, C] and depth1.bounds [K, 4], all K crops voxelized in one pass over the points.
// C is kChannels, or kChannels + kOccupancyChannels (free, unknown from the observation's
// OctoMap) when asked for.
#pragma once

#include <vector>

#include "stream/record.hpp"
#include "voxels/voxel_grid.hpp"

namespace qte::voxels {

struct VoxelsRecordOptions {
  GridBounds scene;
  std::vector<GridBounds> crops;  // the deeper grids, each of scene.voxels per side
  bool occupancy_channels = false;
};

struct VoxelsOfObservation {
  stream::Record record{"voxels"};
  // The grids with kChannels, depth 0 first, then each crop (for pictures).
  std::vector<float> grids;
};

VoxelsOfObservation voxels_of(const stream::Record& obs, const VoxelsRecordOptions& options);

}  // namespace qte::voxels

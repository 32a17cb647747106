// A picture of a voxel grid for people: occupied voxels drawn as cubes in their mean colour
// (or coloured by a value per voxel, e.g. Q), seen from above and in front, as a PNG.
#pragma once

#include <string>
#include <vector>

namespace qte::voxels {

struct VoxelImageOptions {
  int size_px = 512;
  // When not empty (voxels^3 values, order x, y, z): colour by value (turbo colour map,
  // low blue, high red) instead of mean RGB, and draw every voxel above `min_value`.
  std::vector<float> values;
  float min_value = -1e30f;
  // Voxel to outline in red, over everything drawn (e.g. the chosen one), or -1.
  int marked_x = -1, marked_y = -1, marked_z = -1;
};

// `grid` is voxels^3 * kChannels floats as voxelize() writes them. Written atomically.
void save_voxel_png(const std::string& path, const float* grid, int voxels, const VoxelImageOptions& options = {});

}  // namespace qte::voxels

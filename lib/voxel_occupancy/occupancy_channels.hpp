// Optional extra voxel channels from OctoMap (off by default until shown to help learning):
// whether each voxel centre was seen free along a camera ray, or never seen at all. Points
// alone cannot tell "empty" from "hidden"; the camera rays can.
#pragma once

#include <memory>
#include <vector>

#include "stream/record.hpp"
#include "voxels/voxel_grid.hpp"

namespace qte::voxel_occupancy {

constexpr int kOccupancyChannels = 2;  // free, unknown (occupied is channel 9 already)

// The map of one observation: every camera's points inserted as rays from the camera.
class ObservedSpace {
 public:
  explicit ObservedSpace(const stream::Record& obs, double resolution_m = 0.01);
  ~ObservedSpace();
  // voxels^3 * kOccupancyChannels floats for `bounds`, index order x, y, z.
  void channels(const voxels::GridBounds& bounds, float* out) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Interleaves `extra` channels after the kChannels of `grid`: out has kChannels + extra_count.
std::vector<float> append_channels(const float* grid, const float* extra, int voxels, int extra_count);

}  // namespace qte::voxel_occupancy

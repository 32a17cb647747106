// The 'voxels' record voxelize writes after each observation (formats/record-stream.md):
// depth0.grid [V, V, V, C] over the scene bounds and depth0.bounds; with crops, depth1.grid
// [K, V, V, V, C] and depth1.bounds [K, 4], all K crops voxelized in one pass over the points.
// C is kChannels, or kChannels + kOccupancyChannels (free, unknown from the observation's
// OctoMap) when asked for.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "stream/field_names.hpp"
#include "stream/record.hpp"
#include "stream/stage.hpp"
#include "voxels/voxel_grid.hpp"

namespace qte::voxel_occupancy {

struct VoxelsRecordOptions {
  voxels::GridBounds scene;
  std::vector<voxels::GridBounds> crops;  // the deeper grids, each of scene.voxels per side
  bool occupancy_channels = false;
};

struct VoxelsOfObservation {
  stream::Record record{record_type::voxels};
  // The grids with kChannels, depth 0 first, then each crop (for pictures).
  std::vector<float> grids;
};

VoxelsOfObservation voxels_of(const stream::Record& obs, const VoxelsRecordOptions& options);

// The voxelize stage: every record passes through; after each 'obs' its 'voxels' record, made
// from what `prepare` makes of the observation (point-cloud filters) when one is given. With
// `png_dir`, pictures of the grids: <record index>.depth0.png, <record index>.depth1.<crop>.png.
class VoxelizeStage : public stream::Stage {
 public:
  VoxelizeStage(VoxelsRecordOptions options, std::string png_dir = "",
                std::function<stream::Record(const stream::Record&)> prepare = nullptr)
      : options_(std::move(options)), png_dir_(std::move(png_dir)), prepare_(std::move(prepare)) {}
  void handle(const stream::Record& record, const stream::Emit& emit) override;
  std::vector<std::string> reads() const override { return {record_type::obs}; }

 private:
  void save_pictures(uint64_t record_index, const std::vector<float>& grids) const;
  VoxelsRecordOptions options_;
  std::string png_dir_;
  std::function<stream::Record(const stream::Record&)> prepare_;
};

}  // namespace qte::voxel_occupancy

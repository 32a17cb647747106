#include "voxel_occupancy/voxels_record.hpp"

#include <cstdio>
#include <memory>

#include "common/indexed_name.hpp"
#include "stream/field_names.hpp"
#include "voxel_occupancy/occupancy_channels.hpp"
#include "voxels/grid_fields.hpp"
#include "voxels/observation_cloud.hpp"
#include "voxels/voxel_image.hpp"

namespace qte::voxel_occupancy {

using namespace voxels;  // the grids these channels and records are made of

VoxelsOfObservation voxels_of(const stream::Record& obs, const VoxelsRecordOptions& options) {
  const int64_t v = options.scene.voxels, k = static_cast<int64_t>(options.crops.size());
  const std::size_t grid_floats = static_cast<std::size_t>(v * v * v) * kChannels;
  const ObservationCloud cloud = observation_cloud(obs);
  require_points_in_scene(obs, cloud, options.scene);  // an empty grid is refused, as qte-select does
  VoxelsOfObservation out;
  out.grids.resize(grid_floats * (1 + options.crops.size()));
  voxelize(cloud.view(), options.scene, out.grids.data());
  if (!options.crops.empty()) voxelize_many(cloud.view(), options.crops, out.grids.data() + grid_floats);

  std::unique_ptr<ObservedSpace> space;
  if (options.occupancy_channels) space = std::make_unique<ObservedSpace>(obs);
  // Grid `i` of out.grids, with the OctoMap channels appended when asked for.
  const auto with_channels = [&](std::size_t i, const GridBounds& bounds) {
    const float* g = out.grids.data() + i * grid_floats;
    if (!space) return std::vector<float>(g, g + grid_floats);
    std::vector<float> extra(static_cast<std::size_t>(v * v * v) * kOccupancyChannels);
    space->channels(bounds, extra.data());
    return append_channels(g, extra.data(), static_cast<int>(v), kOccupancyChannels);
  };
  const int64_t channels = kChannels + (space ? kOccupancyChannels : 0);
  out.record.set<float>(fields::depth_field(0, fields::per_depth::grid), {v, v, v, channels},
                        with_channels(0, options.scene));
  out.record.set<double>(fields::depth_field(0, fields::per_depth::bounds), {4}, bounds_values(options.scene));
  if (options.crops.empty()) return out;
  std::vector<float> grids;
  std::vector<double> bounds;
  for (std::size_t c = 0; c < options.crops.size(); ++c) {
    const std::vector<float> one = with_channels(1 + c, options.crops[c]);
    grids.insert(grids.end(), one.begin(), one.end());
    const std::vector<double> b = bounds_values(options.crops[c]);
    bounds.insert(bounds.end(), b.begin(), b.end());
  }
  out.record.set<float>(fields::depth_field(1, fields::per_depth::grid), {k, v, v, v, channels}, grids);
  out.record.set<double>(fields::depth_field(1, fields::per_depth::bounds), {k, 4}, bounds);
  return out;
}

void VoxelizeStage::handle(const stream::Record& record, const stream::Emit& emit) {
  emit(record);
  if (record.type() != record_type::obs) return;
  const VoxelsOfObservation out = voxels_of(prepare_ ? prepare_(record) : record, options_);
  if (!png_dir_.empty()) save_pictures(record.position.record_index, out.grids);
  emit(out.record);
}

void VoxelizeStage::save_pictures(uint64_t record_index, const std::vector<float>& grids) const {
  const int v = options_.scene.voxels;
  const std::size_t grid_floats = static_cast<std::size_t>(v) * v * v * kChannels;
  save_voxel_png(png_dir_ + "/" + indexed_name(record_index, "depth0.png"), grids.data(), v);
  for (std::size_t c = 0; c < options_.crops.size(); ++c)
    save_voxel_png(png_dir_ + "/" + indexed_name(record_index, "depth1." + std::to_string(c) + ".png"),
                   grids.data() + (1 + c) * grid_floats, v);
}

}  // namespace qte::voxel_occupancy

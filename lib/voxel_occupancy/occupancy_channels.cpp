#include "voxel_occupancy/occupancy_channels.hpp"

#include "planning/occupancy_scene.hpp"
#include "stream/field_names.hpp"
#include "voxels/observation_cloud.hpp"

namespace qte::voxel_occupancy {

using namespace voxels;  // the grids these channels and records are made of

struct ObservedSpace::Impl {
  planning::OccupancyScene scene;
  explicit Impl(const planning::SceneOptions& options) : scene(options) {}
};

ObservedSpace::ObservedSpace(const stream::Record& obs, double resolution_m) {
  planning::SceneOptions options;
  options.resolution_m = resolution_m;
  impl_ = std::make_unique<Impl>(options);
  for (const std::string& camera : obs.prefixes(fields::per_camera::extrinsics)) {
    const std::string name = camera + fields::per_camera::extrinsics;
    stream::Record one(record_type::obs);  // one camera at a time: its rays start at its own origin
    for (const char* part :
         {fields::per_camera::rgb, fields::per_camera::points, fields::per_camera::depth, fields::per_camera::depth_mm,
          fields::per_camera::intrinsics, fields::per_camera::extrinsics})
      if (obs.has(camera + part)) one.add(obs.field(camera + part));
    one.position = obs.position;
    const ObservationCloud cloud = observation_cloud(one);
    const auto e = obs.array<double>(name);
    impl_->scene.insert_camera(cloud.xyz.data(), cloud.rgb.size() / 3, Eigen::Vector3d(e[3], e[7], e[11]), {}, {});
  }
}

ObservedSpace::~ObservedSpace() = default;

void ObservedSpace::channels(const GridBounds& bounds, float* out) const {
  const int v = bounds.voxels;
  for (int x = 0, flat = 0; x < v; ++x)
    for (int y = 0; y < v; ++y)
      for (int z = 0; z < v; ++z, ++flat) {
        const auto state = impl_->scene.occupancy_at(bounds.centre_of({x, y, z}));
        out[kOccupancyChannels * flat + 0] = state == planning::OccupancyScene::Occupancy::free ? 1.0f : 0.0f;
        out[kOccupancyChannels * flat + 1] = state == planning::OccupancyScene::Occupancy::unknown ? 1.0f : 0.0f;
      }
}

std::vector<float> append_channels(const float* grid, const float* extra, int voxels, int extra_count) {
  const std::size_t cells = static_cast<std::size_t>(voxels) * voxels * voxels;
  const int total = kChannels + extra_count;
  std::vector<float> out(cells * total);
  for (std::size_t i = 0; i < cells; ++i) {
    std::copy(grid + i * kChannels, grid + (i + 1) * kChannels, out.begin() + i * total);
    std::copy(extra + i * extra_count, extra + (i + 1) * extra_count, out.begin() + i * total + kChannels);
  }
  return out;
}

}  // namespace qte::voxel_occupancy

// The 'voxels' record of an observation against the voxelizer called directly: the scene grid,
// the crops (one pass over the points) with their bounds, and the OctoMap channels' layout.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>

#include "sim_step/simulator.hpp"
#include "voxels/grid_fields.hpp"
#include "voxels/observation_cloud.hpp"
#include "voxel_occupancy/occupancy_channels.hpp"
#include "voxel_occupancy/voxels_record.hpp"

using namespace qte;

namespace {

stream::Record first_observation() {
  const robot::RobotModel robot = robot::RobotModel::xarm7();
  sim_step::SimulatorOptions options = sim_step::options_for_cameras({"front"}, 64, 64);
  options.render_threads = 1;
  sim_step::Simulator sim(robot, options);
  stream::Record obs("obs");
  sim.handle(sim_step::plan_reset({"pick_and_lift", 0, 1, 2}, 0), [&](const stream::Record& r) { obs = r; });
  return obs;
}

std::vector<float> field_floats(const stream::Record& r, const std::string& name) {
  const auto a = r.array<float>(name);
  return std::vector<float>(a.begin(), a.end());
}

}  // namespace

TEST(VoxelsRecord, GridsAreTheVoxelizersAndCropsFollowTheScene) {
  const stream::Record obs = first_observation();
  voxel_occupancy::VoxelsRecordOptions options;
  options.crops = {voxels::GridBounds::around({0.2, 0.0, 0.8}, 0.15, 16), voxels::GridBounds::around({0.1, 0.2, 0.9}, 0.15, 16)};
  const voxel_occupancy::VoxelsOfObservation out = voxel_occupancy::voxels_of(obs, options);

  const voxels::ObservationCloud cloud = voxels::observation_cloud(obs);
  const std::size_t floats = 16 * 16 * 16 * voxels::kChannels;
  std::vector<float> expected(floats);
  voxels::voxelize(cloud.view(), options.scene, expected.data());
  EXPECT_EQ(field_floats(out.record, "depth0.grid"), expected);
  EXPECT_EQ(out.record.field("depth0.grid").shape(), (stream::Shape{16, 16, 16, voxels::kChannels}));
  EXPECT_EQ(std::vector<float>(out.grids.begin(), out.grids.begin() + floats), expected);
  std::vector<float> crops;
  for (const auto& crop : options.crops) {
    voxels::voxelize(cloud.view(), crop, expected.data());
    crops.insert(crops.end(), expected.begin(), expected.end());
  }
  EXPECT_EQ(field_floats(out.record, "depth1.grid"), crops);
  EXPECT_EQ(out.record.field("depth1.grid").shape(), (stream::Shape{2, 16, 16, 16, voxels::kChannels}));
  const auto bounds = out.record.array<double>("depth1.bounds");
  EXPECT_EQ(std::vector<double>(bounds.begin() + 4, bounds.begin() + 8), voxels::bounds_values(options.crops[1]));
  int occupied = 0;
  for (std::size_t i = voxels::kChannels - 1; i < floats; i += voxels::kChannels) occupied += out.grids[i] > 0;
  EXPECT_GT(occupied, 20);  // the table and the block are seen
}

TEST(VoxelsRecord, OccupancyChannelsFollowTheTenAndNoCropsMeansNoDepth1) {
  const stream::Record obs = first_observation();
  voxel_occupancy::VoxelsRecordOptions options;
  options.scene.voxels = 8;
  const voxel_occupancy::VoxelsOfObservation plain = voxel_occupancy::voxels_of(obs, options);
  options.occupancy_channels = true;
  const voxel_occupancy::VoxelsOfObservation out = voxel_occupancy::voxels_of(obs, options);
  EXPECT_FALSE(out.record.has("depth1.grid"));
  const int c = voxels::kChannels + voxel_occupancy::kOccupancyChannels;
  EXPECT_EQ(out.record.field("depth0.grid").shape(), (stream::Shape{8, 8, 8, c}));
  const auto with = out.record.array<float>("depth0.grid"), without = plain.record.array<float>("depth0.grid");
  for (int cell = 0; cell < 8 * 8 * 8; ++cell)
    for (int k = 0; k < voxels::kChannels; ++k) ASSERT_EQ(with[cell * c + k], without[cell * voxels::kChannels + k]);
}

// The voxelize stage: every record passes through in order, an 'obs' is followed by its
// 'voxels' record (that of what `prepare` made of it), and pictures are named by record index.
TEST(VoxelizeStage, PassesRecordsThroughAndFollowsEachObservationWithItsVoxels) {
  stream::Record obs = first_observation();
  obs.position.record_index = 4;
  voxel_occupancy::VoxelsRecordOptions options;
  options.crops = {voxels::GridBounds::around({0.2, 0.0, 0.8}, 0.15, 16)};
  const std::string pictures = ::testing::TempDir();
  // Every other pixel's point dropped (NaN: no return): the stage must voxelize this, not the
  // record it passes on. (Dropping all of them would be an empty scene, which is refused.)
  const auto without_points = [](const stream::Record& r) {
    stream::Record thinned = r;
    const auto points = r.array<float>("front.points");
    std::vector<float> kept(points.data, points.data + points.size());
    for (std::size_t i = 0; i < kept.size(); i += 6) kept[i] = kept[i + 1] = kept[i + 2] = NAN;
    thinned.set<float>("front.points", points.shape, kept);
    return thinned;
  };
  int prepared = 0;
  voxel_occupancy::VoxelizeStage stage(options, pictures, [&](const stream::Record& r) {
    ++prepared;
    return without_points(r);
  });
  std::vector<stream::Record> out;
  const stream::Emit keep = [&](const stream::Record& r) { out.push_back(r); };
  stage.handle(stream::Record("reset"), keep);
  stage.handle(obs, keep);
  ASSERT_EQ(out.size(), 3u);
  EXPECT_EQ(out[0].type(), "reset");
  EXPECT_EQ(out[1].type(), "obs");
  EXPECT_EQ(out[1].field("front.points").shape(), obs.field("front.points").shape());  // passed on unchanged
  EXPECT_EQ(out[2].type(), "voxels");
  EXPECT_EQ(prepared, 1);
  EXPECT_EQ(field_floats(out[2], "depth0.grid"),
            field_floats(voxel_occupancy::voxels_of(without_points(obs), options).record, "depth0.grid"));
  EXPECT_NE(field_floats(out[2], "depth0.grid"), field_floats(voxel_occupancy::voxels_of(obs, options).record, "depth0.grid"));
  for (const char* name : {"000004.depth0.png", "000004.depth1.0.png"}) {
    const std::string path = pictures + "/" + name;
    EXPECT_EQ(::access(path.c_str(), R_OK), 0) << path;
    std::remove(path.c_str());
  }
}
